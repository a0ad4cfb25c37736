//! Adam (Kingma and Ba), as PyTorch implements it, and global gradient-norm clipping.

#[derive(Debug, Clone, PartialEq)]
pub struct Adam {
    pub learning_rate: f32,
    pub beta1: f32,
    pub beta2: f32,
    pub epsilon: f32,
    /// First and second moment estimates, one per parameter.
    pub first_moment: Vec<f32>,
    pub second_moment: Vec<f32>,
    pub steps: u64,
}

impl Adam {
    pub fn new(parameters: usize, learning_rate: f32) -> Self {
        Self {
            learning_rate,
            beta1: 0.9,
            beta2: 0.999,
            epsilon: 1e-8,
            first_moment: vec![0.0; parameters],
            second_moment: vec![0.0; parameters],
            steps: 0,
        }
    }

    /// One update of `params` against `grads`.
    pub fn step(&mut self, params: &mut [f32], grads: &[f32]) {
        assert_eq!(params.len(), self.first_moment.len());
        assert_eq!(grads.len(), params.len());
        self.steps += 1;
        let t = self.steps as i32;
        let correction1 = 1.0 - self.beta1.powi(t);
        let correction2 = 1.0 - self.beta2.powi(t);
        let step_size = self.learning_rate / correction1;
        let (b1, b2, eps) = (self.beta1, self.beta2, self.epsilon);
        for (((p, &g), m), v) in params.iter_mut().zip(grads).zip(&mut self.first_moment).zip(&mut self.second_moment) {
            *m = b1 * *m + (1.0 - b1) * g;
            *v = b2 * *v + (1.0 - b2) * g * g;
            *p -= step_size * *m / ((*v / correction2).sqrt() + eps);
        }
    }
}

/// Scales `grads` so their global L2 norm is at most `max_norm`; returns the norm before clipping.
pub fn clip_grad_norm(grads: &mut [f32], max_norm: f32) -> f32 {
    let norm = grads.iter().map(|g| (*g as f64) * (*g as f64)).sum::<f64>().sqrt() as f32;
    if norm > max_norm {
        let scale = max_norm / (norm + 1e-6);
        grads.iter_mut().for_each(|g| *g *= scale);
    }
    norm
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_step_moves_each_parameter_by_the_learning_rate_against_its_gradient() {
        let mut adam = Adam::new(3, 1e-3);
        let mut params = [1.0, -2.0, 0.5];
        adam.step(&mut params, &[0.3, -40.0, 0.0]);
        assert!((params[0] - (1.0 - 1e-3)).abs() < 1e-6);
        assert!((params[1] - (-2.0 + 1e-3)).abs() < 1e-6);
        assert_eq!(params[2], 0.5);
    }

    #[test]
    fn minimizes_a_quadratic() {
        let mut adam = Adam::new(2, 0.05);
        let mut p = [3.0f32, -4.0];
        for _ in 0..2000 {
            let grads = [2.0 * (p[0] - 1.0), 2.0 * (p[1] + 2.0)];
            adam.step(&mut p, &grads);
        }
        assert!((p[0] - 1.0).abs() < 1e-2 && (p[1] + 2.0).abs() < 1e-2, "{p:?}");
    }

    #[test]
    fn clipping_caps_the_global_norm() {
        let mut g = [3.0, 4.0];
        assert_eq!(clip_grad_norm(&mut g, 1.0), 5.0);
        assert!(((g[0] * g[0] + g[1] * g[1]).sqrt() - 1.0).abs() < 1e-5);
        let mut small = [0.3, 0.4];
        clip_grad_norm(&mut small, 1.0);
        assert_eq!(small, [0.3, 0.4]);
    }
}
