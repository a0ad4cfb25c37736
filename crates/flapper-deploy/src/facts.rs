//! What a robot must know around the policy, read from the policy's task and the robot model: written
//! into every export (the ONNX model's metadata, the C header's comments and macros) from this one place.

use std::path::Path;

use flapper_eval::FlightPolicyFile;
use flapper_ppo::checkpoint::CheckpointKind;
use flapper_sim::{ActuatedJoint, N_ACTUATED_JOINTS, RobotModel};
use flapper_task::action::ActionMap;
use flapper_task::config::ActionMode;
use flapper_task::observation::{FRAME_SIZE, ObservationLayout};
use serde::Serialize;

use crate::{DeployError, PolicyArrays};

/// The facts of one policy, in the order docs/deploy.md explains them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DeploymentFacts {
    /// The file exported (its name, not its folder).
    pub source: String,
    /// A policy file, or a checkpoint of a run (possibly still training).
    pub source_kind: CheckpointKind,
    pub training_iteration: usize,
    pub training_env_steps: u64,
    pub observation_size: usize,
    /// Frames of history, oldest first, `frame_size` numbers each (the layout's first part).
    pub history_frames: usize,
    pub frame_size: usize,
    /// The fields of one frame, in order.
    pub frame_fields: Vec<String>,
    /// Reference points ahead, 3 numbers each (x, y, z in the body frame, m), after the history.
    pub lookahead_steps: usize,
    /// A name for every one of the observation's numbers (`ObservationLayout::names`).
    pub observation_names: Vec<String>,
    pub action_size: usize,
    /// What the actions ask for: `joint_targets` (target = action x `action_half_range_rad`).
    pub action_mode: ActionMode,
    /// The joints in the actions' order (q1..q5), as the MJCF names them.
    pub joint_names: [&'static str; N_ACTUATED_JOINTS],
    /// Each joint's range (rad), from the robot model.
    pub joint_ranges_rad: [[f64; 2]; N_ACTUATED_JOINTS],
    /// The joint target (rad) an action of +1 asks for (`action_scale` x the joint's limit).
    pub action_half_range_rad: [f64; N_ACTUATED_JOINTS],
    /// Passive feathering (s; `[task.control] passive_feathering_s`, 0 for a policy trained without it):
    /// each wing's pitch target (q2, q4) plus this times its own flap's rate (q1, q3, rad/s, read when the
    /// action is computed), clipped to the pitch's half range. The twisted target is next step's previous
    /// action.
    pub passive_feathering_s: f64,
    /// The policy's rate: one action per control period.
    pub control_rate_hz: f64,
    pub control_period_s: f64,
    /// The servo loop: the 7 Hz filter and the PD targets are updated every simulation step.
    pub servo_rate_hz: f64,
    pub substeps_per_control_step: usize,
    /// Cutoff of the first-order low-pass filter between the actions' joint targets and the servos.
    pub filter_cutoff_hz: f64,
    /// The normalizer inside the export: clamp((x - mean) / (std + epsilon), -clip, clip).
    pub normalizer_epsilon: f64,
    pub normalizer_clip: f32,
    /// Multiply-adds and float32 bytes of one export.
    pub multiply_adds: usize,
    pub weight_bytes: usize,
}

impl DeploymentFacts {
    /// The facts of the policy in `file` (read from `path`) flying `robot`.
    pub fn of(
        file: &FlightPolicyFile,
        path: &Path,
        arrays: &PolicyArrays,
        robot: &RobotModel,
    ) -> Result<Self, DeployError> {
        let task = &file.task;
        let layout = ObservationLayout::of(&task.observation);
        if layout.clock {
            return Err(DeployError::Clock { path: path.to_owned(), clock_hz: task.observation.clock_hz });
        }
        let sim = robot.instantiate()?;
        let control_period_s = task.control_period_s(robot.timestep_s());
        let actions = ActionMap::new(&sim, &task.control, control_period_s);
        let names = layout.names();
        Ok(Self {
            source: path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned()),
            source_kind: file.info.kind,
            training_iteration: file.info.iteration,
            training_env_steps: file.info.env_steps,
            observation_size: layout.size(),
            history_frames: layout.history_frames,
            frame_size: FRAME_SIZE,
            // The newest frame's names, without their "t-0." prefix.
            frame_fields: names[layout.lookahead_start() - FRAME_SIZE..layout.lookahead_start()]
                .iter()
                .map(|n| n.trim_start_matches("t-0.").to_owned())
                .collect(),
            lookahead_steps: layout.lookahead_steps,
            observation_names: names,
            action_size: arrays.action_size(),
            action_mode: task.control.action_mode,
            joint_names: ActuatedJoint::ALL.map(ActuatedJoint::name),
            joint_ranges_rad: sim.joint_ranges(),
            action_half_range_rad: actions.half_range_rad(),
            passive_feathering_s: task.control.passive_feathering_s,
            control_rate_hz: 1.0 / control_period_s,
            control_period_s,
            servo_rate_hz: 1.0 / robot.timestep_s(),
            substeps_per_control_step: task.control.substeps,
            filter_cutoff_hz: task.control.filter_cutoff_hz,
            normalizer_epsilon: arrays.normalizer_epsilon,
            normalizer_clip: arrays.normalizer_clip,
            multiply_adds: arrays.multiply_adds(),
            weight_bytes: arrays.weight_bytes(),
        })
    }

    /// The facts as (key, value) text pairs sorted by key (ONNX's `metadata_props`): a string as
    /// itself, anything else as JSON (numbers, lists).
    pub fn metadata(&self) -> Vec<(String, String)> {
        let serde_json::Value::Object(fields) = serde_json::to_value(self).expect("the facts serialize") else {
            unreachable!("a struct serializes to an object")
        };
        fields
            .into_iter()
            .map(|(key, value)| match value {
                serde_json::Value::String(text) => (key, text),
                other => (key, other.to_string()),
            })
            .collect()
    }
}
