//! The robustness sweeps: a setting changes what it says in MuJoCo's model and nothing else, the next
//! draw restores the nominal model, and the sweep's success accounting matches the evaluation's.

use std::sync::Arc;

use flapper_analysis::robustness::{
    EnvelopeResult, FluidSeries, RobustnessSettings, Sweep, Tally, default_winds, fluid_randomization, needed_airspeed,
    nominal_randomization, robustness, table_iii_randomization, wind_randomization,
};
use flapper_eval::load_flight_policy;
use flapper_eval::tracking::{TrackingController, evaluate_tracking, evaluate_tracking_randomized};
use flapper_sim::{LIFTING_SURFACE_GEOMS, RobotModel, Vec3};
use flapper_task::TaskConfig;
use flapper_task::randomization::randomize;
use flapper_task::reference::Reference;
use flapper_task::reference::named::named;
use rand::SeedableRng;

/// Tallies agree (NaN RMS, when nothing completed, agrees with NaN).
fn assert_same(a: &Tally, b: &Tally, what: &str) {
    assert_eq!((a.episodes, a.successes, a.success_rate), (b.episodes, b.successes, b.success_rate), "{what}");
    assert_eq!(a.mean_rms_error_m.to_bits(), b.mean_rms_error_m.to_bits(), "{what}: RMS");
}

/// The shipped stage-3 policy and the sharp-turn reference: small runs of the sweeps.
fn stage3_on_sharp_turn() -> (RobotModel, TrackingController, TaskConfig, Arc<Reference>) {
    let robot = RobotModel::flapper().unwrap();
    let path =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies/history/stage3/policy.safetensors");
    let (policy, task) = load_flight_policy(&path).unwrap();
    let reference = Arc::new(named("sharp-turn", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.6).unwrap());
    (robot, TrackingController::Policy(Arc::new(policy)), task, reference)
}

#[test]
fn a_kutta_lift_setting_changes_only_kutta_lift_in_mujoco_and_the_next_draw_restores_it() {
    let robot = RobotModel::flapper().unwrap();
    let mut sim = robot.instantiate().unwrap();
    let nominal: Vec<[f64; 5]> =
        LIFTING_SURFACE_GEOMS.iter().map(|g| sim.fluid_coefficients(g).unwrap().to_array()).collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut kutta_scales = Vec::new();
    for _ in 0..20 {
        randomize(&mut sim, &fluid_randomization(FluidSeries::Kutta, 0.5), &mut rng).unwrap();
        for (geom, nominal) in LIFTING_SURFACE_GEOMS.iter().zip(&nominal) {
            // Read back from MuJoCo's geom_fluid.
            let drawn = sim.fluid_coefficients(geom).unwrap().to_array();
            for i in [0, 1, 2, 4] {
                assert_eq!(drawn[i], nominal[i], "{geom}: coefficient {i} must stay nominal");
            }
            let scale = drawn[3] / nominal[3];
            assert!((0.5..=1.5).contains(&scale), "{geom}: Kutta lift x{scale}, outside [0.5, 1.5]");
            kutta_scales.push(scale);
        }
        assert_eq!(sim.wind(), Vec3::ZERO, "no wind in a fluid setting");
    }
    let (low, high) = kutta_scales.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), s| (l.min(*s), h.max(*s)));
    assert!(low < 0.8 && high > 1.2, "draws should spread over the range, got [{low}, {high}]");

    randomize(&mut sim, &nominal_randomization(), &mut rng).unwrap();
    let restored: Vec<[f64; 5]> =
        LIFTING_SURFACE_GEOMS.iter().map(|g| sim.fluid_coefficients(g).unwrap().to_array()).collect();
    assert_eq!(restored, nominal, "a nominal draw restores the model");

    randomize(&mut sim, &fluid_randomization(FluidSeries::All, 0.3), &mut rng).unwrap();
    let all = sim.fluid_coefficients(LIFTING_SURFACE_GEOMS[0]).unwrap().to_array();
    assert!(
        (0..5).all(|i| all[i] != nominal[0][i] && (all[i] / nominal[0][i] - 1.0).abs() <= 0.3),
        "{all:?} vs {:?}",
        nominal[0]
    );

    randomize(&mut sim, &wind_randomization([-2.0, 1.0, 0.5]), &mut rng).unwrap();
    assert_eq!(sim.wind(), Vec3::new(-2.0, 1.0, 0.5), "a wind setting is a constant wind");
    let still = sim.fluid_coefficients(LIFTING_SURFACE_GEOMS[1]).unwrap().to_array();
    assert_eq!(still, nominal[1]);
}

#[test]
fn the_sweep_counts_the_evaluation_s_completed_episodes() {
    let (robot, controller, task, reference) = stage3_on_sharp_turn();
    let settings = RobustnessSettings {
        sweeps: vec![Sweep::Fluid, Sweep::Wind],
        episodes: 6,
        seed: 3,
        ranges: vec![0.0, 0.5],
        winds: vec![[0.0; 3], [0.0, 0.0, 2.0]],
    };
    assert_eq!(settings.settings_count(), 6 * 2 + 2);
    let calls = std::sync::atomic::AtomicUsize::new(0);
    let (report, paths) = robustness(&robot, &controller, &task, reference.clone(), &settings, &|_| {
        calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    })
    .unwrap();
    assert_eq!(calls.into_inner(), settings.settings_count(), "one progress call per setting");
    assert_eq!(report.fluid.len(), 12);
    assert_eq!(report.wind.len(), 2);
    assert_eq!(paths.len(), 2);

    // Range 0 with nothing drawn is the plain evaluation: same starts, same outcomes.
    let plain = Tally::of(&evaluate_tracking(&robot, &controller, &task, reference.clone(), 6, 3).unwrap());
    for row in report.fluid.iter().filter(|f| f.range == 0.0) {
        assert_same(&row.tally, &plain, &format!("{} at r = 0", row.coefficient));
    }
    assert_same(&report.wind[0].tally, &plain, "still air");
    // Each setting's tally is the count of completed episodes of that setting's evaluation.
    for row in report.fluid.iter().filter(|f| f.range == 0.5) {
        let series = FluidSeries::ALL.into_iter().find(|s| s.name() == row.coefficient).unwrap();
        let results = evaluate_tracking_randomized(
            &robot,
            &controller,
            &task,
            &fluid_randomization(series, 0.5),
            reference.clone(),
            6,
            3,
        )
        .unwrap();
        let completed = results.iter().filter(|r| r.completed()).count();
        assert_eq!((row.tally.episodes, row.tally.successes), (6, completed), "{}", row.coefficient);
        assert_eq!(row.tally.success_rate, completed as f64 / 6.0);
    }
    assert!(report.table_iii.is_none() && report.envelope.is_none(), "only the sweeps asked for run");
}

#[test]
fn the_default_winds_cover_the_axes_at_1_and_2_m_s_and_table_iii_s_corners() {
    let winds = default_winds();
    assert_eq!(winds.len(), 1 + 12 + 8);
    assert!(winds.contains(&[-2.0, 0.0, 0.0]) && winds.contains(&[0.0, 1.0, 0.0]) && winds.contains(&[0.0, 0.0, -1.0]));
    assert!(winds.contains(&[2.0, -2.0, 1.5]) && winds.contains(&[-2.0, 2.0, -1.5]));
}

#[test]
fn a_tailwind_asks_for_less_airspeed_and_the_envelope_says_whether_the_robot_has_it() {
    // Cruise: 30 s straight and level at 3.8 m/s along +x.
    let cruise = named("cruise", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.6).unwrap();
    let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
    let still = needed_airspeed(&cruise, [0.0; 3]);
    assert!(close(still.slowest_mps, 3.8) && close(still.fastest_mps, 3.8), "{still:?}");
    let tail = needed_airspeed(&cruise, [1.0, 0.0, 0.0]);
    assert!(close(tail.slowest_mps, 2.8) && close(tail.fastest_mps, 2.8), "{tail:?}");
    let head = needed_airspeed(&cruise, [-2.0, 0.0, 0.0]);
    assert!(close(head.slowest_mps, 5.8), "{head:?}");
    let cross = needed_airspeed(&cruise, [0.0, 1.0, 0.0]);
    assert!(close(cross.slowest_mps, (3.8f64 * 3.8 + 1.0).sqrt()), "{cross:?}");
    // The longitudinal path climbs and dives: its needs spread.
    let longitudinal = needed_airspeed(&named("longitudinal", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.6).unwrap(), [0.0; 3]);
    assert!(longitudinal.slowest_mps >= 3.8 - 1e-9 && longitudinal.fastest_mps > 4.0, "{longitudinal:?}");

    let envelope = |lo, hi| EnvelopeResult {
        speeds: Vec::new(),
        slowest_sustained_mps: lo,
        fastest_sustained_mps: hi,
        fastest_flown_mps: 8.0,
    };
    assert_eq!(tail.inside(&envelope(Some(3.0), Some(8.0))), Some(false), "2.8 m/s is slower than 3 m/s");
    assert_eq!(tail.inside(&envelope(Some(2.5), Some(8.0))), Some(true));
    assert_eq!(head.inside(&envelope(Some(3.0), Some(5.5))), Some(false), "5.8 m/s is faster than 5.5 m/s");
    // Sustained up to the fastest airspeed flown: the top is unknown, so nothing is too fast.
    let gale = needed_airspeed(&cruise, [-5.0, 0.0, 0.0]);
    assert!(close(gale.fastest_mps, 8.8));
    assert_eq!(gale.inside(&envelope(Some(3.0), Some(8.0))), Some(true));
    assert_eq!(
        gale.inside(&envelope(Some(3.0), Some(7.5))),
        Some(false),
        "8.8 m/s is faster than 7.5 m/s, and 8 was flown"
    );
    assert_eq!(still.inside(&envelope(None, None)), None, "no envelope, no judgement");
}

#[test]
fn table_iii_is_also_counted_over_the_episodes_whose_wind_the_envelope_allows() {
    let (robot, controller, task, reference) = stage3_on_sharp_turn();
    let settings = RobustnessSettings {
        sweeps: vec![Sweep::TableIii, Sweep::Envelope],
        episodes: 6,
        seed: 2,
        ranges: vec![],
        winds: vec![],
    };
    let (report, _) = robustness(&robot, &controller, &task, reference.clone(), &settings, &|_| {}).unwrap();
    let envelope = report.envelope.as_ref().unwrap();
    assert!(envelope.slowest_sustained_mps.is_some(), "the stage-3 policy sustains some level airspeed");
    let inside = report.table_iii_inside_envelope.expect("both sweeps ran");

    // The same episodes flown again: each recorded the wind it drew from Table III's box.
    let results =
        evaluate_tracking_randomized(&robot, &controller, &task, &table_iii_randomization(), reference.clone(), 6, 2)
            .unwrap();
    assert_same(&Tally::of(&results), report.table_iii.as_ref().unwrap(), "Table III");
    for r in &results {
        let w = r.wind_mps;
        assert!(w != Vec3::ZERO && w.x.abs() <= 2.0 && w.y.abs() <= 2.0 && w.z.abs() <= 1.5, "{w:?}");
    }
    let allowed: Vec<_> = results
        .iter()
        .filter(|r| needed_airspeed(&reference, r.wind_mps.to_array()).inside(envelope) == Some(true))
        .collect();
    assert_eq!(inside.episodes, allowed.len());
    assert_eq!(inside.successes, allowed.iter().filter(|r| r.completed()).count());
    // Unrandomized episodes fly in still air.
    assert!(evaluate_tracking(&robot, &controller, &task, reference, 1, 2).unwrap()[0].wind_mps == Vec3::ZERO);
}
