//! Third-order continuous-time transfer functions fitted to sampled input-output records, in the
//! paper's form (eqs. 9-11): Y(s)/U(s) = (b2 s^2 + b1 s + b0) / (s^3 + a2 s^2 + a1 s + a0).
//!
//! Method: state-variable filtering (Young's SVF; Ljung, System Identification, 2nd ed., sec. 7.4).
//! Input and output both pass through the same filter 1/(s + lambda)^3, whose states are the filtered
//! signal and its first three derivatives. The differential equation of the model holds for the
//! filtered signals exactly as for the raw ones, so
//! y_f''' = -a2 y_f'' - a1 y_f' - a0 y_f + b2 u_f'' + b1 u_f' + b0 u_f
//! is linear in the coefficients: ordinary least squares (nalgebra's SVD). Several axes can share the
//! denominator (one regression, a numerator block per axis). The filter's start-up transient is
//! skipped.

use nalgebra::{DMatrix, DVector};

use crate::linear_system::TransferFunction;

/// One record of one axis: input and output sampled every `FitSettings::dt_s`, same length.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    pub input: Vec<f64>,
    pub output: Vec<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitSettings {
    pub dt_s: f64,
    /// lambda of the filter 1/(s + lambda)^3 (rad/s): near the band of interest.
    pub filter_pole_radps: f64,
    /// Seconds at the start of each record left out of the regression (filter start-up).
    pub skip_s: f64,
}

impl Default for FitSettings {
    fn default() -> Self {
        Self { dt_s: 0.02, filter_pole_radps: 2.0, skip_s: 4.0 }
    }
}

/// `signal` through 1/(s + lambda)^3 from rest: per sample, the filtered signal and its derivatives
/// of order 0 to 3 (RK4, input interpolated linearly between samples).
pub fn state_variable_filter(signal: &[f64], dt_s: f64, lambda: f64) -> Vec<[f64; 4]> {
    // (s + l)^3 = s^3 + 3 l s^2 + 3 l^2 s + l^3; states x = (w, w', w'').
    let (d2, d1, d0) = (3.0 * lambda, 3.0 * lambda * lambda, lambda.powi(3));
    let third = |x: [f64; 3], u: f64| u - d2 * x[2] - d1 * x[1] - d0 * x[0];
    let derivative = |x: [f64; 3], u: f64| [x[1], x[2], third(x, u)];
    let step = |x: [f64; 3], h: f64, k: [f64; 3]| [x[0] + h * k[0], x[1] + h * k[1], x[2] + h * k[2]];
    let mut x = [0.0; 3];
    let mut out = Vec::with_capacity(signal.len());
    for k in 0..signal.len() {
        out.push([x[0], x[1], x[2], third(x, signal[k])]);
        let (u0, u1) = (signal[k], *signal.get(k + 1).unwrap_or(&signal[k]));
        let um = 0.5 * (u0 + u1);
        let k1 = derivative(x, u0);
        let k2 = derivative(step(x, 0.5 * dt_s, k1), um);
        let k3 = derivative(step(x, 0.5 * dt_s, k2), um);
        let k4 = derivative(step(x, dt_s, k3), u1);
        for i in 0..3 {
            x[i] += dt_s / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    out
}

/// Fits one third-order model per axis, all with one shared denominator (`axes[i]` holds axis i's
/// records). `None` if there is too little data or the least-squares problem is degenerate.
pub fn fit_common_denominator(axes: &[Vec<Record>], settings: &FitSettings) -> Option<Vec<TransferFunction>> {
    let skip = (settings.skip_s / settings.dt_s).ceil() as usize;
    let columns = 3 + 3 * axes.len();
    let mut rows: Vec<(Vec<f64>, f64)> = Vec::new();
    for (axis, records) in axes.iter().enumerate() {
        for record in records {
            if record.input.len() != record.output.len() {
                return None;
            }
            let u = state_variable_filter(&record.input, settings.dt_s, settings.filter_pole_radps);
            let y = state_variable_filter(&record.output, settings.dt_s, settings.filter_pole_radps);
            for k in skip..u.len() {
                let mut row = vec![0.0; columns];
                row[..3].copy_from_slice(&[-y[k][2], -y[k][1], -y[k][0]]);
                row[3 + 3 * axis..6 + 3 * axis].copy_from_slice(&[u[k][2], u[k][1], u[k][0]]);
                rows.push((row, y[k][3]));
            }
        }
    }
    if rows.len() < 4 * columns {
        return None;
    }
    let a = DMatrix::from_fn(rows.len(), columns, |i, j| rows[i].0[j]);
    let b = DVector::from_iterator(rows.len(), rows.iter().map(|r| r.1));
    let theta = a.svd(true, true).solve(&b, 1e-12).ok()?;
    if !theta.iter().all(|v| v.is_finite()) {
        return None;
    }
    let denominator = vec![1.0, theta[0], theta[1], theta[2]];
    (0..axes.len())
        .map(|axis| TransferFunction::new(theta.rows(3 + 3 * axis, 3).iter().copied().collect(), denominator.clone()))
        .collect()
}

/// Goodness of a model on records it was not fitted to: the model's response from rest, compared
/// after the first `skip_s` seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Validation {
    /// Mean squared error of the predicted output (m^2 for positions).
    pub mse: f64,
    /// 100 (1 - |y - y_model| / |y - mean(y)|): 100 is a perfect fit, 0 no better than the mean.
    pub fit_percent: f64,
}

pub fn validate(model: &TransferFunction, records: &[Record], settings: &FitSettings) -> Validation {
    let skip = (settings.skip_s / settings.dt_s).ceil() as usize;
    let (mut error2, mut count, mut measured) = (0.0, 0usize, Vec::new());
    let mut residuals = Vec::new();
    for record in records {
        let predicted = model.simulate(&record.input, settings.dt_s);
        for (&output, &prediction) in record.output.iter().zip(&predicted).skip(skip) {
            let e = output - prediction;
            error2 += e * e;
            count += 1;
            measured.push(output);
            residuals.push(e);
        }
    }
    let mean = measured.iter().sum::<f64>() / measured.len().max(1) as f64;
    let spread = measured.iter().map(|y| (y - mean).powi(2)).sum::<f64>().sqrt();
    let residual = residuals.iter().map(|e| e * e).sum::<f64>().sqrt();
    Validation { mse: error2 / count.max(1) as f64, fit_percent: 100.0 * (1.0 - residual / spread.max(1e-300)) }
}
