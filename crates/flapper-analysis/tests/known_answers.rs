//! The identification recovers known systems: the paper's eq. 9 (and 11) from noisy records excited
//! the way `flapper sysid` excites the robot.

use flapper_analysis::fit::{FitSettings, Record, fit_common_denominator, validate};
use flapper_analysis::linear_system::TransferFunction;
use flapper_analysis::sysid::{DataSet, FlownRecord, SysidSettings, identify, multisine};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const PAPER_DENOMINATOR: [f64; 4] = [1.0, 3.554, 6.438, 2.809];

fn records(system: &TransferFunction, seeds: std::ops::Range<u64>, noise_m: f64, axis: usize) -> Vec<Record> {
    seeds
        .map(|seed| {
            let input = multisine(seed, axis, 1500, 0.02, &SysidSettings::default());
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

/// Records of an anticipating closed loop: per axis, `truth` driven by the target perturbation
/// `lead` control steps ahead, with white output noise of `noise_m`.
fn anticipating_records(truths: &[(TransferFunction, usize); 3], s: &SysidSettings, noise_m: f64) -> Vec<FlownRecord> {
    let dt_s = 0.02;
    let n = (s.record_s() / dt_s).round() as usize;
    let skip = (s.skip_s() / dt_s).round() as usize;
    let lookahead = 30;
    let mut records = Vec::new();
    for (axis, (truth, lead)) in truths.iter().enumerate() {
        let plan = (0..s.identification_records as u64)
            .map(|i| (DataSet::Identification, i))
            .chain((0..s.validation_records as u64).map(|i| (DataSet::Validation, 500 + i)));
        for (set, seed) in plan {
            let target: Vec<f64> =
                multisine(seed, axis, n + lookahead, dt_s, s).iter().map(|v| v * s.amplitude_m).collect();
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed ^ axis as u64);
            let output = truth
                .simulate(&target[*lead..lead + n], dt_s)
                .into_iter()
                .map(|y| y + noise_m * (rng.random::<f64>() - 0.5) * 2.0)
                .collect();
            let time_s = (1..=n).map(|k| k as f64 * dt_s).collect();
            records.push(FlownRecord { set, axis, seed, time_s, target, output, skip });
        }
    }
    records
}

fn roots_within(found: &[num_complex::Complex64], truth: &[num_complex::Complex64], tolerance: f64, what: &str) {
    assert_eq!(found.len(), truth.len(), "{what}: {found:?}");
    for p in truth {
        let nearest = found.iter().map(|q| (q - p).norm()).fold(f64::INFINITY, f64::min);
        assert!(nearest <= tolerance * p.norm(), "{what} {p} not recovered: found {found:?}");
    }
}

#[test]
fn an_anticipating_closed_loop_is_recovered_with_its_lead_poles_and_zeros() {
    let den = PAPER_DENOMINATOR.to_vec();
    // Zeros: x -3.13 and -0.168 (the paper's), y -2 and -5, z -0.51 +- 1.89i (the paper's).
    let truths = [
        (TransferFunction::new(vec![49.89, 164.9, 26.27], den.clone()).unwrap(), 15),
        (TransferFunction::new(vec![0.3, 2.1, 3.0], den.clone()).unwrap(), 5),
        (TransferFunction::new(vec![1.006, 1.020, 3.836], den).unwrap(), 25),
    ];
    let s = SysidSettings { averaged_periods: 3, ..SysidSettings::default() };
    let records = anticipating_records(&truths, &s, 1e-3);
    let identified = identify(&records, &s).unwrap();
    assert_eq!(identified.leads, [15, 5, 25], "the leads (control steps of 0.02 s)");
    for (axis, ((truth, _), found)) in truths.iter().zip(&identified.models).enumerate() {
        roots_within(&found.poles(), &truth.poles(), 0.05, &format!("axis {axis}: pole"));
        roots_within(&found.zeros(), &truth.zeros(), 0.1, &format!("axis {axis}: zero"));
        let reported = identified.report.per_axis.each()[axis].1;
        assert!(reported.fit_percent > 95.0 && reported.bibo_stable && reported.minimum_phase, "{reported:?}");
        assert!((reported.input_lead_s - truths[axis].1 as f64 * 0.02).abs() < 1e-9);
    }
    // A model without the lead (the paper's input) predicts the same records clearly worse.
    let without = identify(&records, &SysidSettings { input_lead_s: Some(0.0), ..s.clone() }).unwrap();
    for (axis, m) in without.report.per_axis.each() {
        let with = identified.report.per_axis.each().iter().find(|(a, _)| *a == axis).unwrap().1.fit_percent;
        assert!(m.fit_percent < with - 1.0, "{axis}: {} without the lead, {with} with it", m.fit_percent);
    }
}

#[test]
fn the_measured_responses_own_fit_is_near_100_percent_for_a_linear_loop_and_not_for_a_saturating_one() {
    let den = PAPER_DENOMINATOR.to_vec();
    let truths = [
        (TransferFunction::new(vec![49.89, 164.9, 26.27], den.clone()).unwrap(), 15),
        (TransferFunction::new(vec![0.3, 2.1, 3.0], den.clone()).unwrap(), 5),
        (TransferFunction::new(vec![1.006, 1.020, 3.836], den).unwrap(), 25),
    ];
    let s = SysidSettings { averaged_periods: 3, ..SysidSettings::default() };
    let linear = anticipating_records(&truths, &s, 1e-3);
    let identified = identify(&linear, &s).unwrap();
    for (axis, selection) in identified.report.order_selection.iter().enumerate() {
        let model_fit = identified.report.per_axis.each()[axis].1.fit_percent;
        assert!(selection.nonparametric_fit_percent > 97.0, "axis {axis}: {}", selection.nonparametric_fit_percent);
        assert!((selection.nonparametric_fit_percent - model_fit).abs() < 3.0, "axis {axis}: model {model_fit}");
    }
    // The same loops with their output clipped at half its RMS: each multisine is distorted its own way.
    let saturating: Vec<FlownRecord> = linear
        .into_iter()
        .map(|mut r| {
            let rms = (r.output.iter().map(|y| y * y).sum::<f64>() / r.output.len() as f64).sqrt();
            r.output.iter_mut().for_each(|y| *y = y.clamp(-0.5 * rms, 0.5 * rms));
            r
        })
        .collect();
    let clipped = identify(&saturating, &s).unwrap();
    for (axis, selection) in clipped.report.order_selection.iter().enumerate() {
        let best_model = selection.orders.iter().map(|o| o.fit_percent).fold(f64::NEG_INFINITY, f64::max);
        assert!(selection.nonparametric_fit_percent < 90.0, "axis {axis}: {}", selection.nonparametric_fit_percent);
        assert!(best_model < selection.nonparametric_fit_percent + 5.0, "axis {axis}: best model {best_model}");
    }
}
