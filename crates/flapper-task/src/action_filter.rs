//! The 7 Hz low-pass filter between the controller's joint targets and the PD servos (paper III-A).
//! It limits the flapping frequencies a controller can use (4-6 Hz pass, faster strokes are damped).

use flapper_sim::N_ACTUATED_JOINTS;

/// First-order low-pass filter, one state per joint, discretised exactly for a step input held over
/// each sample: y += alpha (u - y), alpha = 1 - exp(-2 pi f_c dt).
#[derive(Debug, Clone)]
pub struct LowPassFilter {
    alpha: f64,
    state: [f64; N_ACTUATED_JOINTS],
}

impl LowPassFilter {
    /// A filter with cutoff `cutoff_hz` updated every `sample_period_s`.
    pub fn new(cutoff_hz: f64, sample_period_s: f64) -> Self {
        let alpha = 1.0 - (-std::f64::consts::TAU * cutoff_hz * sample_period_s).exp();
        Self { alpha, state: [0.0; N_ACTUATED_JOINTS] }
    }

    /// Sets the output to `value` (no transient from the previous episode).
    pub fn reset(&mut self, value: [f64; N_ACTUATED_JOINTS]) {
        self.state = value;
    }

    /// Feeds one sample and returns the filtered output.
    pub fn update(&mut self, input: &[f64; N_ACTUATED_JOINTS]) -> [f64; N_ACTUATED_JOINTS] {
        for (y, u) in self.state.iter_mut().zip(input) {
            *y += self.alpha * (u - *y);
        }
        self.state
    }

    pub fn output(&self) -> [f64; N_ACTUATED_JOINTS] {
        self.state
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steady-state amplitude ratio of a sine at `frequency_hz` through the 7 Hz filter at 250 Hz.
    fn gain_at(frequency_hz: f64) -> f64 {
        let dt = 0.004;
        let mut filter = LowPassFilter::new(7.0, dt);
        let mut peak: f64 = 0.0;
        for k in 0..5000 {
            let u = (std::f64::consts::TAU * frequency_hz * k as f64 * dt).sin();
            let y = filter.update(&[u; N_ACTUATED_JOINTS])[0];
            if k > 2500 {
                peak = peak.max(y.abs());
            }
        }
        peak
    }

    #[test]
    fn cutoff_attenuates_7_hz_by_3_db() {
        let g = gain_at(7.0);
        assert!((g - std::f64::consts::FRAC_1_SQRT_2).abs() < 0.03, "gain at 7 Hz: {g}");
    }

    #[test]
    fn flapping_band_passes_and_fast_strokes_are_damped() {
        assert!(gain_at(1.0) > 0.98);
        assert!(gain_at(5.3) > 0.75);
        assert!(gain_at(20.0) < 0.36);
        assert!(gain_at(20.0) < gain_at(7.0) && gain_at(7.0) < gain_at(5.3));
    }

    #[test]
    fn a_step_settles_and_reset_removes_history() {
        let mut filter = LowPassFilter::new(7.0, 0.004);
        for _ in 0..200 {
            filter.update(&[1.0; N_ACTUATED_JOINTS]);
        }
        assert!((filter.output()[3] - 1.0).abs() < 1e-6);
        filter.reset([0.2; N_ACTUATED_JOINTS]);
        assert_eq!(filter.output(), [0.2; N_ACTUATED_JOINTS]);
    }
}
