//! Continuous-time linear systems as transfer functions N(s) / D(s): roots of polynomials (eigenvalues
//! of the companion matrix, with nalgebra), poles, zeros, DC gain, the verdicts the paper draws from
//! them (BIBO stable: every pole in the open left half plane; minimum phase: every zero there too),
//! and simulation of the response to a sampled input.

use nalgebra::DMatrix;
use num_complex::Complex64;
use serde::Serialize;

/// Roots of the polynomial with `coefficients` (highest power first). Leading zeros are dropped; a
/// constant has no roots.
pub fn roots(coefficients: &[f64]) -> Vec<Complex64> {
    let first = coefficients.iter().position(|&c| c != 0.0);
    let Some(first) = first else { return Vec::new() };
    let c = &coefficients[first..];
    let degree = c.len() - 1;
    if degree == 0 {
        return Vec::new();
    }
    // Companion matrix of the monic polynomial: its eigenvalues are the roots.
    let mut companion = DMatrix::<f64>::zeros(degree, degree);
    for j in 0..degree {
        companion[(0, j)] = -c[j + 1] / c[0];
    }
    for i in 1..degree {
        companion[(i, i - 1)] = 1.0;
    }
    let mut found: Vec<Complex64> = companion.complex_eigenvalues().iter().copied().collect();
    found.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
    found
}

/// A polynomial in s, highest power first, as text: `+1.0000 s^2 +0.5000 s +0.2500`.
pub fn polynomial_text(coefficients: &[f64]) -> String {
    let degree = coefficients.len().saturating_sub(1);
    coefficients
        .iter()
        .enumerate()
        .map(|(i, c)| match degree - i {
            0 => format!("{c:+.4}"),
            1 => format!("{c:+.4} s"),
            p => format!("{c:+.4} s^{p}"),
        })
        .collect::<Vec<_>>()
        .join(" ")
}

/// Evaluates the polynomial (highest power first) at `s`.
pub fn evaluate(coefficients: &[f64], s: Complex64) -> Complex64 {
    coefficients.iter().fold(Complex64::new(0.0, 0.0), |acc, &c| acc * s + c)
}

/// N(s) / D(s), coefficients highest power first; strictly proper (degree N < degree D).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransferFunction {
    pub numerator: Vec<f64>,
    pub denominator: Vec<f64>,
}

impl TransferFunction {
    /// Normalizes the denominator to be monic. `None` if it is not strictly proper or D's leading
    /// coefficient is zero.
    pub fn new(numerator: Vec<f64>, denominator: Vec<f64>) -> Option<Self> {
        let lead = *denominator.first()?;
        if lead == 0.0 || !lead.is_finite() || numerator.len() >= denominator.len() {
            return None;
        }
        Some(Self {
            numerator: numerator.iter().map(|c| c / lead).collect(),
            denominator: denominator.iter().map(|c| c / lead).collect(),
        })
    }

    pub fn order(&self) -> usize {
        self.denominator.len() - 1
    }

    pub fn poles(&self) -> Vec<Complex64> {
        roots(&self.denominator)
    }

    pub fn zeros(&self) -> Vec<Complex64> {
        roots(&self.numerator)
    }

    /// N(0) / D(0): the steady-state output per unit of constant input.
    pub fn dc_gain(&self) -> f64 {
        let (n, d) = (self.numerator.last().copied().unwrap_or(0.0), self.denominator.last().copied().unwrap_or(0.0));
        n / d
    }

    /// N(j omega) / D(j omega): gain and phase of the steady response to a sine of `omega_radps`.
    pub fn frequency_response(&self, omega_radps: f64) -> Complex64 {
        let s = Complex64::new(0.0, omega_radps);
        evaluate(&self.numerator, s) / evaluate(&self.denominator, s)
    }

    /// Every pole in the open left half plane.
    pub fn bibo_stable(&self) -> bool {
        self.poles().iter().all(|p| p.re < 0.0)
    }

    /// Every zero in the open left half plane (a system without zeros is minimum phase).
    pub fn minimum_phase(&self) -> bool {
        self.zeros().iter().all(|z| z.re < 0.0)
    }

    /// The response from rest to `input` sampled every `dt_s` (controllable canonical form, RK4 with
    /// the input interpolated linearly between samples).
    pub fn simulate(&self, input: &[f64], dt_s: f64) -> Vec<f64> {
        let n = self.order();
        // y = sum_i c_i x_{i+1}, with c_i the coefficient of s^i in N.
        let mut c = vec![0.0; n];
        for (i, coefficient) in self.numerator.iter().rev().enumerate() {
            c[i] = *coefficient;
        }
        let d: Vec<f64> = self.denominator[1..].to_vec();
        let derivative = |x: &[f64], u: f64| -> Vec<f64> {
            let mut dx = vec![0.0; n];
            dx[..n - 1].copy_from_slice(&x[1..n]);
            dx[n - 1] = u - (0..n).map(|i| d[n - 1 - i] * x[i]).sum::<f64>();
            dx
        };
        let output = |x: &[f64]| x.iter().zip(&c).map(|(a, b)| a * b).sum::<f64>();
        let mut x = vec![0.0; n];
        let mut y = Vec::with_capacity(input.len());
        for k in 0..input.len() {
            y.push(output(&x));
            let (u0, u1) = (input[k], *input.get(k + 1).unwrap_or(&input[k]));
            let um = 0.5 * (u0 + u1);
            let axpy = |a: &[f64], h: f64, b: &[f64]| a.iter().zip(b).map(|(p, q)| p + h * q).collect::<Vec<_>>();
            let k1 = derivative(&x, u0);
            let k2 = derivative(&axpy(&x, 0.5 * dt_s, &k1), um);
            let k3 = derivative(&axpy(&x, 0.5 * dt_s, &k2), um);
            let k4 = derivative(&axpy(&x, dt_s, &k3), u1);
            for i in 0..n {
                x[i] += dt_s / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        y
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Complex64, re: f64, im: f64) -> bool {
        (a.re - re).abs() < 1e-9 && (a.im - im).abs() < 1e-9
    }

    #[test]
    fn roots_of_polynomials_with_known_roots() {
        // (s + 1)(s + 2)(s - 3) = s^3 - 7 s - 6
        let r = roots(&[1.0, 0.0, -7.0, -6.0]);
        assert!(close(r[0], -2.0, 0.0) && close(r[1], -1.0, 0.0) && close(r[2], 3.0, 0.0), "{r:?}");
        // 2 (s^2 + 2 s + 5): -1 +- 2i; leading zeros are ignored.
        let r = roots(&[0.0, 2.0, 4.0, 10.0]);
        assert!(close(r[0], -1.0, -2.0) && close(r[1], -1.0, 2.0), "{r:?}");
        assert!(roots(&[3.0]).is_empty() && roots(&[0.0, 0.0]).is_empty());
    }

    #[test]
    fn verdicts_on_stable_unstable_and_non_minimum_phase_systems() {
        let stable = TransferFunction::new(vec![1.0, 2.0], vec![1.0, 3.0, 2.0]).unwrap(); // zero -2, poles -1, -2
        assert!(stable.bibo_stable() && stable.minimum_phase());
        assert!((stable.dc_gain() - 1.0).abs() < 1e-12);
        let rhp_pole = TransferFunction::new(vec![1.0], vec![1.0, -1.0, -2.0]).unwrap(); // poles 2, -1
        assert!(!rhp_pole.bibo_stable() && rhp_pole.minimum_phase());
        let rhp_zero = TransferFunction::new(vec![-1.0, 2.0], vec![1.0, 3.0, 2.0]).unwrap(); // zero +2
        assert!(rhp_zero.bibo_stable() && !rhp_zero.minimum_phase());
        assert!(TransferFunction::new(vec![1.0, 0.0], vec![1.0, 0.0]).is_none(), "not strictly proper");
    }

    #[test]
    fn simulated_step_response_settles_at_the_dc_gain_with_the_first_order_time_constant() {
        // 2 / (s + 0.5): y(t) = 4 (1 - exp(-t / 2)).
        let tf = TransferFunction::new(vec![2.0], vec![1.0, 0.5]).unwrap();
        let y = tf.simulate(&vec![1.0; 1001], 0.02);
        assert!((y[100] - 4.0 * (1.0 - (-1.0f64).exp())).abs() < 1e-6, "{}", y[100]);
        assert!((y[1000] - 4.0).abs() < 1e-3);
    }
}
