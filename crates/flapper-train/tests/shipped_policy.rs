//! The committed policies still fly: each completes the 30 s cruise reference from randomized starts.
//! This guards every later change to the model, the task or the learner.

use std::path::PathBuf;
use std::sync::Arc;

use flapper_eval::tracking::{Pilot, evaluate_tracking};
use flapper_sim::{RobotModel, Vec3};
use flapper_task::reference::named::named;
use flapper_train::run::load_flight_policy;

fn shipped(stage: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies").join(stage).join("policy.safetensors")
}

#[test]
fn the_shipped_stage_1_policy_still_flies_the_cruise() {
    let robot = RobotModel::flapper().unwrap();
    let (policy, task) = load_flight_policy(&shipped("stage1")).unwrap();
    let reference = named("cruise", Vec3::new(0.0, 0.0, 10.0), 0.02, task.observation.lookahead_steps as f64 * 0.02).unwrap();
    let results = evaluate_tracking(&robot, &Pilot::Policy(Arc::new(policy)), &task, Arc::new(reference), 4, 7).unwrap();
    for (k, r) in results.iter().enumerate() {
        assert!(r.completed(), "episode {k} ended {:?} after {} steps", r.end, r.steps.len());
        assert!(r.rms_error_m() < 1.5, "episode {k}: RMS error {:.2} m", r.rms_error_m());
    }
}
