//! The identification recovers known systems: the paper's eq. 9 (and 11) from noisy records excited
//! the way `flapper sysid` excites the robot.

use flapper_analysis::fit::{FitSettings, Record, fit_common_denominator, validate};
use flapper_analysis::linear_system::TransferFunction;
use flapper_analysis::sysid::multisine;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const PAPER_DENOMINATOR: [f64; 4] = [1.0, 3.554, 6.438, 2.809];

fn records(system: &TransferFunction, seeds: std::ops::Range<u64>, noise_m: f64, axis: usize) -> Vec<Record> {
    seeds
        .map(|seed| {
            let input = multisine(seed, axis, 1500, 0.02);
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0xabc);
            let output = system
                .simulate(&input, 0.02)
                .into_iter()
                .map(|y| y + noise_m * (rng.random::<f64>() - 0.5) * 2.0)
                .collect();
            Record { input, output }
        })
        .collect()
}

fn poles_within(found: &TransferFunction, truth: &TransferFunction, tolerance: f64) {
    let (f, t) = (found.poles(), truth.poles());
    assert_eq!(f.len(), t.len());
    for p in &t {
        let nearest = f.iter().map(|q| (q - p).norm()).fold(f64::INFINITY, f64::min);
        assert!(nearest <= tolerance * p.norm(), "pole {p} not recovered: found {f:?}");
    }
}

#[test]
fn recovers_the_papers_x_axis_system_from_noisy_multisine_records() {
    let truth = TransferFunction::new(vec![49.89, 164.9, 26.27], PAPER_DENOMINATOR.to_vec()).unwrap();
    let settings = FitSettings::default();
    // Output noise of 2% of the response's RMS.
    let clean = records(&truth, 1..2, 0.0, 0);
    let rms = (clean[0].output.iter().map(|y| y * y).sum::<f64>() / 1500.0).sqrt();
    let identification = records(&truth, 1..5, 0.02 * rms, 0);
    let fitted = fit_common_denominator(&[identification], &settings).unwrap().remove(0);
    poles_within(&fitted, &truth, 0.05);
    assert!(fitted.bibo_stable() && fitted.minimum_phase());
    assert!((fitted.dc_gain() - truth.dc_gain()).abs() < 0.05 * truth.dc_gain().abs());
    let validation = validate(&fitted, &records(&truth, 100..102, 0.0, 0), &settings);
    assert!(validation.fit_percent > 95.0, "{validation:?}");
}

#[test]
fn a_shared_denominator_is_recovered_from_three_axes() {
    let den = PAPER_DENOMINATOR.to_vec();
    let x = TransferFunction::new(vec![49.89, 164.9, 26.27], den.clone()).unwrap();
    let y = TransferFunction::new(vec![-0.09798, -10.07, -24.67], den.clone()).unwrap();
    let z = TransferFunction::new(vec![1.006, 1.020, 3.836], den).unwrap();
    let axes: Vec<Vec<Record>> = [&x, &y, &z].iter().enumerate().map(|(i, s)| records(s, 1..4, 1e-3, i)).collect();
    let fitted = fit_common_denominator(&axes, &FitSettings::default()).unwrap();
    for (found, truth) in fitted.iter().zip([&x, &y, &z]) {
        poles_within(found, truth, 0.05);
        assert_eq!(found.denominator, fitted[0].denominator);
        assert!((found.dc_gain() - truth.dc_gain()).abs() < 0.05 * truth.dc_gain().abs(), "{found:?}");
    }
    // The paper's y-axis zeros (about -2.5 and -100) lie in the left half plane.
    assert!(fitted[1].minimum_phase());
}

#[test]
fn a_system_with_a_right_half_plane_zero_is_identified_as_non_minimum_phase() {
    // (s - 1) (s + 2) over the paper's denominator: a zero at +1.
    let truth = TransferFunction::new(vec![1.0, 1.0, -2.0], PAPER_DENOMINATOR.to_vec()).unwrap();
    let fitted = fit_common_denominator(&[records(&truth, 1..4, 1e-3, 2)], &FitSettings::default()).unwrap().remove(0);
    assert!(fitted.bibo_stable() && !fitted.minimum_phase(), "{:?}", fitted.zeros());
}
