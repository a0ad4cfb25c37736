//! The committed policies still fly: they complete the 30 s cruise reference from the nominal start and
//! from most randomized starts, close to the path. This guards every later change to the model, the task
//! or the learner (a change that breaks the learned flight fails here).

use std::path::PathBuf;
use std::sync::Arc;

use flapper_eval::tracking::{Pilot, evaluate_tracking};
use flapper_sim::{RobotModel, Vec3};
use flapper_task::reference::named::named;
use flapper_train::run::load_flight_policy;

fn check_flies(stage: &str) {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies").join(stage).join("policy.safetensors");
    let robot = RobotModel::flapper().unwrap();
    let (policy, task) = load_flight_policy(&path).unwrap();
    let pilot = Pilot::Policy(Arc::new(policy));
    let lookahead_s = task.observation.lookahead_steps as f64 * 0.02;
    let reference = Arc::new(named("cruise", Vec3::new(0.0, 0.0, 10.0), 0.02, lookahead_s).unwrap());

    let mut nominal = task.clone();
    nominal.initial_state.position_offset_m = [0.0; 3];
    nominal.initial_state.speed_offset_mps = 0.0;
    nominal.initial_state.attitude_offset_deg = 0.0;
    let exact = &evaluate_tracking(&robot, &pilot, &nominal, reference.clone(), 1, 1).unwrap()[0];
    assert!(exact.completed(), "{stage}: nominal start ended {:?} after {} steps", exact.end, exact.steps.len());
    assert!(exact.rms_error_m() < 0.3, "{stage}: nominal start RMS error {:.2} m", exact.rms_error_m());

    let results = evaluate_tracking(&robot, &pilot, &task, reference, 10, 7).unwrap();
    let completed: Vec<_> = results.iter().filter(|r| r.completed()).collect();
    assert!(completed.len() >= 7, "{stage}: only {} of 10 randomized starts completed", completed.len());
    for r in completed {
        assert!(r.rms_error_m() < 0.5, "{stage}: RMS error {:.2} m", r.rms_error_m());
    }
}

#[test]
fn the_shipped_stage_1_policy_still_flies_the_cruise() {
    check_flies("stage1");
}

#[test]
fn the_shipped_stage_2_policy_still_flies_the_cruise() {
    check_flies("stage2");
}
