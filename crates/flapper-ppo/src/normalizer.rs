//! Running mean and variance of the observations (rsl_rl's `EmpiricalNormalization`), updated from
//! every training batch and frozen at evaluation. Saved with the policy: a policy is only meaningful
//! with the statistics it was trained on.

/// Per-feature running statistics in f64 (a few million samples would lose precision in f32).
#[derive(Debug, Clone, PartialEq)]
pub struct Normalizer {
    pub mean: Vec<f64>,
    pub variance: Vec<f64>,
    /// Samples seen so far.
    pub count: f64,
}

/// Added to the standard deviation so constant features do not divide by zero.
pub const EPSILON: f64 = 1e-2;
/// Normalized values are clipped to +- this, so a feature that was constant in training cannot blow up.
pub const CLIP: f32 = 10.0;

impl Normalizer {
    pub fn new(size: usize) -> Self {
        Self { mean: vec![0.0; size], variance: vec![1.0; size], count: 0.0 }
    }

    pub fn size(&self) -> usize {
        self.mean.len()
    }

    /// These statistics with `extra` features after their own, each as [`Normalizer::new`] starts one.
    pub fn with_features_appended(&self, extra: usize) -> Self {
        let fresh = Self::new(extra);
        Self {
            mean: [&self.mean[..], &fresh.mean].concat(),
            variance: [&self.variance[..], &fresh.variance].concat(),
            count: self.count,
        }
    }

    /// Merges a batch of `rows.len() / size()` observations into the statistics (Chan et al.'s
    /// parallel update, exact for any batch split).
    pub fn update(&mut self, rows: &[f32]) {
        let size = self.size();
        let n = (rows.len() / size) as f64;
        if n == 0.0 {
            return;
        }
        let mut batch_mean = vec![0.0f64; size];
        for row in rows.chunks_exact(size) {
            for (m, &x) in batch_mean.iter_mut().zip(row) {
                *m += x as f64;
            }
        }
        batch_mean.iter_mut().for_each(|m| *m /= n);
        let mut batch_var = vec![0.0f64; size];
        for row in rows.chunks_exact(size) {
            for ((v, &x), m) in batch_var.iter_mut().zip(row).zip(&batch_mean) {
                let d = x as f64 - m;
                *v += d * d;
            }
        }
        batch_var.iter_mut().for_each(|v| *v /= n);
        let total = self.count + n;
        for i in 0..size {
            let delta = batch_mean[i] - self.mean[i];
            let first = if self.count == 0.0 { 0.0 } else { self.variance[i] * self.count };
            self.mean[i] += delta * n / total;
            self.variance[i] = (first + batch_var[i] * n + delta * delta * self.count * n / total) / total;
        }
        self.count = total;
    }

    /// Feature `i`'s frozen mean and scale as [`Normalizer::normalize`] applies them, in f32:
    /// `clamp((x - mean) * scale, -CLIP, CLIP)` with `scale = 1 / (sqrt(variance) + EPSILON)` computed in
    /// f64 (what an exported policy holds, so that it normalizes to the same bits).
    pub fn frozen_feature(&self, i: usize) -> (f32, f32) {
        (self.mean[i] as f32, (1.0 / (self.variance[i].sqrt() + EPSILON)) as f32)
    }

    /// Writes (x - mean) / (std + eps), clipped, for every row of `rows` into `out`.
    pub fn normalize(&self, rows: &[f32], out: &mut Vec<f32>) {
        let size = self.size();
        out.resize(rows.len(), 0.0);
        let feature = |i: usize| self.frozen_feature(i);
        if rows.len() == size {
            // One observation (the on-board controller's call): no buffers to allocate.
            for (i, (dst, &x)) in out.iter_mut().zip(rows).enumerate() {
                let (mean, scale) = feature(i);
                *dst = ((x - mean) * scale).clamp(-CLIP, CLIP);
            }
            return;
        }
        let (mean, scale): (Vec<f32>, Vec<f32>) = (0..size).map(feature).unzip();
        for (row, dst) in rows.chunks_exact(size).zip(out.chunks_exact_mut(size)) {
            for i in 0..size {
                dst[i] = ((row[i] - mean[i]) * scale[i]).clamp(-CLIP, CLIP);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batched_updates_equal_the_statistics_of_all_samples() {
        let data: Vec<f32> = (0..60).map(|i| ((i * 7919) % 97) as f32 * 0.1 - 3.0).collect();
        let mut whole = Normalizer::new(3);
        whole.update(&data);
        let mut parts = Normalizer::new(3);
        parts.update(&data[..9]);
        parts.update(&data[9..33]);
        parts.update(&data[33..]);
        for i in 0..3 {
            let column: Vec<f64> = data.iter().skip(i).step_by(3).map(|&x| x as f64).collect();
            let mean = column.iter().sum::<f64>() / column.len() as f64;
            let var = column.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / column.len() as f64;
            assert!((whole.mean[i] - mean).abs() < 1e-9 && (parts.mean[i] - mean).abs() < 1e-9);
            assert!((whole.variance[i] - var).abs() < 1e-9 && (parts.variance[i] - var).abs() < 1e-9);
        }
        assert_eq!(parts.count, 20.0);
    }

    #[test]
    fn normalized_features_have_zero_mean_unit_variance_and_are_clipped() {
        let data: Vec<f32> = (0..1000).flat_map(|i| [i as f32, 5.0]).collect();
        let mut n = Normalizer::new(2);
        n.update(&data);
        let mut out = Vec::new();
        n.normalize(&data, &mut out);
        let first: Vec<f32> = out.iter().step_by(2).copied().collect();
        let mean = first.iter().sum::<f32>() / 1000.0;
        let var = first.iter().map(|x| (x - mean) * (x - mean)).sum::<f32>() / 1000.0;
        assert!(mean.abs() < 1e-3 && (var - 1.0).abs() < 1e-3, "{mean} {var}");
        assert!(out.iter().skip(1).step_by(2).all(|&x| x == 0.0), "a constant feature maps to 0");
        n.normalize(&[0.0, 1e6], &mut out);
        assert_eq!(out[1], CLIP);
    }

    #[test]
    fn one_row_alone_normalizes_to_the_same_bits_as_in_a_batch() {
        let data: Vec<f32> = (0..300).map(|i| ((i * 7919) % 101) as f32 * 0.37 - 11.0).collect();
        let mut n = Normalizer::new(3);
        n.update(&data);
        let (mut batch, mut single) = (Vec::new(), Vec::new());
        n.normalize(&data, &mut batch);
        for (row, expected) in data.chunks_exact(3).zip(batch.chunks_exact(3)) {
            n.normalize(row, &mut single);
            assert_eq!(
                single.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                expected.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
            );
        }
    }
}
