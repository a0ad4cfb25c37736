//! The committed policies still fly: the hand-chained stages 1-2 (`policies/history/`) complete the 30 s cruise reference from the nominal
//! start and from most randomized starts, close to the path; stage 3 flies the turns of `lateral` and
//! the `loop` from randomized starts; the hand-chained stage 4 the aerobatic chain and the sharp turn;
//! the final controller (`policies/final`, from `flapper curriculum`) the aerobatic chain, the loop
//! and the lateral turns; the flight-modes candidate (`policies/experiments/smooth`) longitudinal on little energy
//! and the aerobatic chain. This guards every later change to the model, the task or the learner (a
//! change that breaks the learned flight fails here).

use std::path::PathBuf;
use std::sync::Arc;

use flapper_eval::load_flight_policy;
use flapper_eval::tracking::{EpisodeResult, TrackingController, evaluate_tracking};
use flapper_sim::{RobotModel, Vec3};
use flapper_task::TaskConfig;
use flapper_task::reference::named::named;

/// The shipped policy in `policies/<stage>` (`final`, `history/stage3`, ...), its task, and the named `reference` with the policy's lookahead.
fn shipped(
    stage: &str,
    reference: &str,
) -> (RobotModel, TrackingController, TaskConfig, Arc<flapper_task::reference::Reference>) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies").join(stage).join("policy.safetensors");
    let robot = RobotModel::flapper().unwrap();
    let (policy, task) = load_flight_policy(&path).unwrap();
    let lookahead_s = task.observation.lookahead_steps as f64 * 0.02;
    let reference = Arc::new(named(reference, Vec3::new(0.0, 0.0, 10.0), 0.02, lookahead_s).unwrap());
    (robot, TrackingController::Policy(Arc::new(policy)), task, reference)
}

/// Flies `reference` from `starts` randomized starts (seed 7): at least `min_completed` complete, each
/// with an RMS error below `max_rms_m`.
fn check_tracks(
    stage: &str,
    reference: &str,
    starts: usize,
    min_completed: usize,
    max_rms_m: f64,
) -> Vec<EpisodeResult> {
    let (robot, controller, task, path) = shipped(stage, reference);
    let results = evaluate_tracking(&robot, &controller, &task, path, starts, 7).unwrap();
    let completed: Vec<_> = results.iter().filter(|r| r.completed()).collect();
    assert!(
        completed.len() >= min_completed,
        "{stage} on {reference}: only {} of {starts} randomized starts completed ({:?})",
        completed.len(),
        results.iter().map(|r| r.end).collect::<Vec<_>>()
    );
    for r in completed {
        assert!(r.rms_error_m() < max_rms_m, "{stage} on {reference}: RMS error {:.2} m", r.rms_error_m());
    }
    results
}

/// At least 3 of 4 randomized starts through the aerobatic chain, each going over the top of its loop.
fn check_flies_the_aerobatic_chain(stage: &str) {
    let results = check_tracks(stage, "aerobatic", 4, 3, 1.0);
    assert!(
        results.iter().filter(|r| r.completed()).all(|r| r.went_inverted()),
        "{stage}: the aerobatic chain's loop goes over the top"
    );
}

fn check_flies_the_cruise(stage: &str) {
    let (robot, controller, task, reference) = shipped(stage, "cruise");
    let mut nominal = task.clone();
    nominal.initial_state.position_offset_m = [0.0; 3];
    nominal.initial_state.speed_offset_mps = 0.0;
    nominal.initial_state.attitude_offset_deg = 0.0;
    let exact = &evaluate_tracking(&robot, &controller, &nominal, reference, 1, 1).unwrap()[0];
    assert!(exact.completed(), "{stage}: nominal start ended {:?} after {} steps", exact.end, exact.steps.len());
    assert!(exact.rms_error_m() < 0.3, "{stage}: nominal start RMS error {:.2} m", exact.rms_error_m());
    check_tracks(stage, "cruise", 10, 7, 0.5);
}

#[test]
fn the_shipped_stage_1_policy_still_flies_the_cruise() {
    check_flies_the_cruise("history/stage1");
}

#[test]
fn the_shipped_stage_2_policy_still_flies_the_cruise() {
    check_flies_the_cruise("history/stage2");
}

#[test]
fn the_shipped_stage_3_policy_flies_the_lateral_turns_and_the_loop() {
    check_tracks("history/stage3", "lateral", 4, 4, 0.5);
    let results = check_tracks("history/stage3", "loop", 4, 4, 1.0);
    // Through the loop and out of it: upside down on the way, back within 1 m of the path after it.
    for r in &results {
        assert!(r.went_inverted(), "a loop goes over the top");
        assert!(r.time_to_rejoin_s(6.0, 1.0).is_some_and(|t| t < 3.0), "rejoined after the loop");
    }
}

#[test]
fn the_shipped_stage_4_policy_flies_the_aerobatic_chain_and_the_sharp_turn() {
    // 99/100 on `aerobatic` and 100/100 on `sharp-turn` (seed 11, 100 episodes).
    check_flies_the_aerobatic_chain("history/stage4");
    check_tracks("history/stage4", "sharp-turn", 4, 4, 1.0);
}

#[test]
fn the_final_controller_flies_the_aerobatic_chain_the_loop_and_the_lateral_turns() {
    // `make evaluate` (seed 11, 100 episodes): aerobatic 96/100, loop and lateral 100/100, lateral at RMS 0.29 m.
    check_flies_the_aerobatic_chain("final");
    check_tracks("final", "loop", 4, 3, 1.0);
    check_tracks("final", "lateral", 4, 4, 0.4);
}

#[test]
fn the_flight_modes_candidate_flies_longitudinal_on_a_third_of_the_final_controllers_energy() {
    // policies/experiments/smooth (configs/experiments/stage4-smooth.toml; seed 11, 100 episodes): longitudinal 100/100 at RMS
    // 0.299 m and 3.59 J/m (the final controller 13.03, the scripted gait 2.40), the aerobatic chain 98/100.
    let results = check_tracks("experiments/smooth", "longitudinal", 4, 4, 0.5);
    for r in &results {
        let energy = r.energy_per_metre_j(0.02);
        assert!(
            energy < 4.8,
            "policies/experiments/smooth on longitudinal: {energy:.2} J/m, over twice the scripted gait's"
        );
    }
    check_flies_the_aerobatic_chain("experiments/smooth");
}
