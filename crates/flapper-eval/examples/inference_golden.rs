//! Writes the golden actions that `tests/inference_golden.rs` checks bit for bit: observations from real
//! flights of a policy (and copies of some made large enough to saturate the normalizer and the
//! actions), with the actions the policy gives them. Run once when the shipped policy changes:
//!
//!     cargo run --release -p flapper-eval --example inference_golden -- POLICY OUT
//!
//! (the test's data: `policies/history/stage4/policy.safetensors crates/flapper-eval/tests/data/inference_golden.safetensors`).
//! Never edit the output by hand: it is what makes "the same bits on every CPU" checkable.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use flapper_eval::load_flight_policy;
use flapper_eval::tracking::{TrackingController, record_episode};
use flapper_ppo::InferenceScratch;
use flapper_sim::{RobotModel, Vec3};
use flapper_task::reference::named::named;
use safetensors::tensor::{Dtype, TensorView};

/// References flown, the episode (randomized start) of each, and every how many control steps an
/// observation is kept.
const FLIGHTS: [(&str, usize); 5] =
    [("aerobatic", 0), ("sharp-turn", 1), ("lateral", 2), ("longitudinal", 3), ("roll-off-the-bottom", 4)];
const KEEP_EVERY: usize = 25;
/// Copies of every fourth kept observation, scaled by each of these (4: beyond anything flown; 50: every
/// feature far into the normalizer's clip).
const SCALES: [f32; 2] = [4.0, 50.0];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [policy_path, out] = args.as_slice() else {
        return Err("usage: inference_golden POLICY OUT".into());
    };
    let robot = RobotModel::flapper()?;
    let (policy, task) = load_flight_policy(&PathBuf::from(policy_path))?;
    let policy = Arc::new(policy);
    let controller = TrackingController::Policy(policy.clone());
    let period_s = task.control_period_s(robot.timestep_s());
    let lookahead_s = task.observation.lookahead_steps as f64 * period_s;
    let mut observations: Vec<Vec<f32>> = Vec::new();
    for (name, episode) in FLIGHTS {
        let reference = named(name, Vec3::new(0.0, 0.0, 10.0), period_s, lookahead_s)
            .ok_or_else(|| format!("no named reference {name}"))?;
        let (_, record) = record_episode(&robot, &controller, &task, Arc::new(reference), 1, episode)?;
        observations.extend(record.observations.into_iter().step_by(KEEP_EVERY));
    }
    let flown = observations.len();
    for scale in SCALES {
        let scaled: Vec<Vec<f32>> =
            observations[..flown].iter().step_by(4).map(|o| o.iter().map(|x| x * scale).collect()).collect();
        observations.extend(scaled);
    }
    let flat: Vec<f32> = observations.concat();
    let mut actions = Vec::new();
    policy.act_deterministic(&flat, &mut InferenceScratch::default(), &mut actions);

    let bytes = |values: &[f32]| values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
    let (observation_bytes, action_bytes) = (bytes(&flat), bytes(&actions));
    let rows = observations.len();
    let views = [
        ("observations", TensorView::new(Dtype::F32, vec![rows, policy.observation_size()], &observation_bytes)?),
        ("actions", TensorView::new(Dtype::F32, vec![rows, policy.action_size()], &action_bytes)?),
    ];
    let metadata = HashMap::from([
        ("policy".to_owned(), policy_path.clone()),
        (
            "made_by".to_owned(),
            format!("cargo run --release -p flapper-eval --example inference_golden -- {policy_path} {out}"),
        ),
    ]);
    std::fs::write(out, safetensors::serialize(views, Some(metadata))?)?;
    let largest = actions.iter().fold(0.0f32, |m, a| m.max(a.abs()));
    println!("wrote {out}: {rows} observations ({flown} flown, the rest scaled), largest |action| {largest:.2}");
    Ok(())
}
