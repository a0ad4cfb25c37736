//! Continuous-time transfer functions fitted to sampled input-output records: n poles and n - 1
//! zeros, the paper's form (eqs. 9-11) for n = 3: Y(s)/U(s) = (b2 s^2 + b1 s + b0) / (s^3 + a2 s^2 +
//! a1 s + a0).
//!
//! Method: state-variable filtering (Young's SVF; Ljung, System Identification, 2nd ed., sec. 7.4).
//! Input and output both pass through the same filter 1/(s + lambda)^n, whose states are the filtered
//! signal and its first n derivatives. The differential equation of the model holds for the
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

/// `signal` through 1/(s + lambda)^`order` from rest: per sample, the filtered signal and its
/// derivatives of order 0 to `order` (RK4, input interpolated linearly between samples).
pub fn state_variable_filter(signal: &[f64], dt_s: f64, lambda: f64, order: usize) -> Vec<Vec<f64>> {
    // (s + l)^n = sum_i C(n, i) l^(n - i) s^i; states x = (w, w', ..., w^(n-1)).
    let binomial = |n: usize, i: usize| (0..i).fold(1.0, |c, k| c * (n - k) as f64 / (k + 1) as f64);
    let d: Vec<f64> = (0..order).map(|i| binomial(order, i) * lambda.powi((order - i) as i32)).collect();
    let highest = |x: &[f64], u: f64| u - x.iter().zip(&d).map(|(a, b)| a * b).sum::<f64>();
    let derivative = |x: &[f64], u: f64| -> Vec<f64> {
        let mut dx: Vec<f64> = x[1..].to_vec();
        dx.push(highest(x, u));
        dx
    };
    let step = |x: &[f64], h: f64, k: &[f64]| x.iter().zip(k).map(|(a, b)| a + h * b).collect::<Vec<f64>>();
    let mut x = vec![0.0; order];
    let mut out = Vec::with_capacity(signal.len());
    for k in 0..signal.len() {
        let mut row = x.clone();
        row.push(highest(&x, signal[k]));
        out.push(row);
        let (u0, u1) = (signal[k], *signal.get(k + 1).unwrap_or(&signal[k]));
        let um = 0.5 * (u0 + u1);
        let k1 = derivative(&x, u0);
        let k2 = derivative(&step(&x, 0.5 * dt_s, &k1), um);
        let k3 = derivative(&step(&x, 0.5 * dt_s, &k2), um);
        let k4 = derivative(&step(&x, dt_s, &k3), u1);
        for i in 0..order {
            x[i] += dt_s / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    out
}

/// Fits one third-order model per axis (the paper's eq. 9 form), all with one shared denominator
/// (`axes[i]` holds axis i's records). `None` if there is too little data or the least-squares
/// problem is degenerate.
pub fn fit_common_denominator(axes: &[Vec<Record>], settings: &FitSettings) -> Option<Vec<TransferFunction>> {
    fit_order(axes, settings, 3)
}

/// As [`fit_common_denominator`] for `order` poles and `order - 1` zeros:
/// y_f^(n) = -a_(n-1) y_f^(n-1) - ... - a0 y_f + b_(n-1) u_f^(n-1) + ... + b0 u_f.
pub fn fit_order(axes: &[Vec<Record>], settings: &FitSettings, order: usize) -> Option<Vec<TransferFunction>> {
    if order == 0 {
        return None;
    }
    let skip = (settings.skip_s / settings.dt_s).ceil() as usize;
    let columns = order + order * axes.len();
    let mut rows: Vec<(Vec<f64>, f64)> = Vec::new();
    for (axis, records) in axes.iter().enumerate() {
        for record in records {
            if record.input.len() != record.output.len() {
                return None;
            }
            let u = state_variable_filter(&record.input, settings.dt_s, settings.filter_pole_radps, order);
            let y = state_variable_filter(&record.output, settings.dt_s, settings.filter_pole_radps, order);
            for k in skip..u.len() {
                // Coefficients highest power first: a_(n-1) .. a_0, then this axis's b_(n-1) .. b_0.
                let mut row = vec![0.0; columns];
                for i in 0..order {
                    row[i] = -y[k][order - 1 - i];
                    row[order + order * axis + i] = u[k][order - 1 - i];
                }
                rows.push((row, y[k][order]));
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
    let denominator: Vec<f64> = std::iter::once(1.0).chain(theta.rows(0, order).iter().copied()).collect();
    (0..axes.len())
        .map(|axis| {
            TransferFunction::new(
                theta.rows(order + order * axis, order).iter().copied().collect(),
                denominator.clone(),
            )
        })
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
