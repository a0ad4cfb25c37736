//! The flapping frequency of a joint signal: the strongest frequency of its spectrum (mean removed)
//! and the fraction of the signal's energy in it. The paper reports 5.3 Hz with 37-39 % of the energy
//! in that one frequency for flap, wing pitch and tail.

use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fundamental {
    pub frequency_hz: f64,
    /// Energy in the peak's frequency bin and its two neighbours (spectral leakage of a finite
    /// record) over the energy of the whole signal without its mean.
    pub energy_fraction: f64,
}

/// The fundamental of `signal` sampled at `sample_rate_hz`; `None` for fewer than 16 samples or a
/// constant signal.
pub fn fundamental(signal: &[f64], sample_rate_hz: f64) -> Option<Fundamental> {
    let n = signal.len();
    if n < 16 {
        return None;
    }
    let mean = signal.iter().sum::<f64>() / n as f64;
    let mut buffer: Vec<Complex<f64>> = signal.iter().map(|x| Complex::new(x - mean, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buffer);
    // One-sided power (Parseval: the sum over all bins equals n times the signal energy).
    let power: Vec<f64> = buffer.iter().map(|c| c.norm_sqr()).collect();
    let total: f64 = power.iter().sum();
    if total <= 1e-12 {
        return None;
    }
    let half = n / 2;
    let peak = (1..=half).max_by(|&a, &b| power[a].total_cmp(&power[b]))?;
    // Both halves of the spectrum hold the same energy for a real signal.
    let band: f64 = (peak.saturating_sub(1).max(1)..=(peak + 1).min(half))
        .map(|k| if 2 * k == n { power[k] } else { 2.0 * power[k] })
        .sum();
    Some(Fundamental { frequency_hz: peak as f64 * sample_rate_hz / n as f64, energy_fraction: band / total })
}

/// How far `signal` leads `reference` (deg, in (-180, 180]) at `frequency_hz`: the phase of each one's
/// Fourier component there (means removed), `signal`'s minus `reference`'s. A wing pitch ahead of its flap
/// by a quarter period (the scripted gait's feathering) reads 90. `None` for signals of different
/// lengths, fewer than 16 samples, or a component of either that is (numerically) absent.
pub fn phase_lead_deg(reference: &[f64], signal: &[f64], frequency_hz: f64, sample_rate_hz: f64) -> Option<f64> {
    if reference.len() != signal.len() || reference.len() < 16 {
        return None;
    }
    let component = |values: &[f64]| {
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        let omega = std::f64::consts::TAU * frequency_hz / sample_rate_hz;
        values
            .iter()
            .enumerate()
            .fold(Complex::new(0.0, 0.0), |sum, (k, v)| sum + Complex::from_polar(v - mean, -omega * k as f64))
    };
    let (r, s) = (component(reference), component(signal));
    if r.norm() < 1e-9 || s.norm() < 1e-9 {
        return None;
    }
    let lead = (s.arg() - r.arg()).to_degrees();
    Some(if lead > 180.0 {
        lead - 360.0
    } else if lead <= -180.0 {
        lead + 360.0
    } else {
        lead
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_phase_lead_of_a_shifted_sine_is_its_shift() {
        let rate = 50.0;
        let wave = |lead_deg: f64| -> Vec<f64> {
            (0..500)
                .map(|k| 0.2 + (std::f64::consts::TAU * 5.3 * k as f64 / rate + lead_deg.to_radians()).sin())
                .collect()
        };
        for lead in [90.0, 45.0, 0.0, -75.0, 170.0] {
            let read = phase_lead_deg(&wave(0.0), &wave(lead), 5.3, rate).unwrap();
            assert!((read - lead).abs() < 1.0, "{lead}: {read}");
        }
        assert_eq!(phase_lead_deg(&wave(0.0), &[0.3; 500], 5.3, rate), None, "a still signal has no phase");
        assert_eq!(phase_lead_deg(&wave(0.0), &wave(0.0)[..400], 5.3, rate), None);
    }

    #[test]
    fn finds_a_sine_and_splits_energy_between_two() {
        let rate = 50.0;
        let t = |k: usize| k as f64 / rate;
        let pure: Vec<f64> = (0..1000).map(|k| 0.3 + (2.0 * std::f64::consts::PI * 5.3 * t(k)).sin()).collect();
        let f = fundamental(&pure, rate).unwrap();
        assert!((f.frequency_hz - 5.3).abs() < 0.06, "{f:?}");
        assert!(f.energy_fraction > 0.9, "{f:?}");
        // Equal amplitudes at 5 and 11 Hz: the peak holds about half the energy.
        let two: Vec<f64> = (0..1000)
            .map(|k| {
                (2.0 * std::f64::consts::PI * 5.0 * t(k)).sin()
                    + 0.99 * (2.0 * std::f64::consts::PI * 11.0 * t(k)).sin()
            })
            .collect();
        let f = fundamental(&two, rate).unwrap();
        assert!((f.frequency_hz - 5.0).abs() < 0.06 && (f.energy_fraction - 0.5).abs() < 0.05, "{f:?}");
        assert!(fundamental(&[1.0; 100], rate).is_none());
    }
}
