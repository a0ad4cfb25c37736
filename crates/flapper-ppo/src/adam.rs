//! Adam (Kingma and Ba), as PyTorch implements it, and global gradient-norm clipping.

use rayon::prelude::*;

/// Parameters per slice handed to a thread wherever the learner works on parameters element by element
/// (Adam, the chunks' gradient sum): large enough to amortize handing out, small enough to balance.
pub(crate) const PARAMETER_SLICE: usize = 8192;

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

    /// One update of `params` against `grads`, the parameters shared out over `threads` threads in
    /// slices (each parameter's update is its own: the same bits on any thread count).
    pub fn step(&mut self, params: &mut [f32], grads: &[f32], threads: usize) {
        assert_eq!(params.len(), self.first_moment.len());
        assert_eq!(grads.len(), params.len());
        self.steps += 1;
        let t = self.steps as i32;
        let correction1 = 1.0 - self.beta1.powi(t);
        let correction2 = 1.0 - self.beta2.powi(t);
        let step_size = self.learning_rate / correction1;
        let (b1, b2, eps) = (self.beta1, self.beta2, self.epsilon);
        let update = |(((p, g), m), v): Slices| {
            for (((p, &g), m), v) in p.iter_mut().zip(g).zip(m).zip(v) {
                *m = b1 * *m + (1.0 - b1) * g;
                *v = b2 * *v + (1.0 - b2) * g * g;
                *p -= step_size * *m / ((*v / correction2).sqrt() + eps);
            }
        };
        if threads >= 2 {
            params
                .par_chunks_mut(PARAMETER_SLICE)
                .zip(grads.par_chunks(PARAMETER_SLICE))
                .zip(self.first_moment.par_chunks_mut(PARAMETER_SLICE))
                .zip(self.second_moment.par_chunks_mut(PARAMETER_SLICE))
                .for_each(update);
        } else {
            update((((params, grads), &mut self.first_moment[..]), &mut self.second_moment[..]));
        }
    }
}

/// One slice of the parameters with its gradients and first and second moments, as zipped iterators pair them.
type Slices<'a> = (((&'a mut [f32], &'a [f32]), &'a mut [f32]), &'a mut [f32]);

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
        adam.step(&mut params, &[0.3, -40.0, 0.0], 1);
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
            adam.step(&mut p, &grads, 1);
        }
        assert!((p[0] - 1.0).abs() < 1e-2 && (p[1] + 2.0).abs() < 1e-2, "{p:?}");
    }

    #[test]
    fn threads_update_each_parameter_as_one_thread_does() {
        let grads: Vec<f32> = (0..20_000).map(|i| ((i * 7919) % 1000) as f32 * 1e-3 - 0.5).collect();
        let start: Vec<f32> = (0..20_000).map(|i| ((i * 104_729) % 997) as f32 * 1e-2).collect();
        let (mut one, mut three) = (Adam::new(20_000, 1e-3), Adam::new(20_000, 1e-3));
        let (mut p1, mut p3) = (start.clone(), start);
        for _ in 0..3 {
            one.step(&mut p1, &grads, 1);
            three.step(&mut p3, &grads, 3);
        }
        assert_eq!(one, three);
        assert!(p1.iter().zip(&p3).all(|(a, b)| a.to_bits() == b.to_bits()));
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
