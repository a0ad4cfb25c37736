//! Single-thread cost of stepping the robot: microseconds per MuJoCo step and per 20 ms control
//! step (5 substeps), as medians over repeated timed blocks. Used by `flapper bench`.

use std::time::Instant;

use crate::error::ModelError;
use crate::geometry::Vec3;
use crate::model::RobotModel;
use crate::simulator::InitialState;

/// Timing of one benchmark run.
#[derive(Debug, Clone)]
pub struct StepTiming {
    /// Median over blocks of the mean time per `mj_step` (microseconds).
    pub median_us_per_mj_step: f64,
    pub min_us_per_mj_step: f64,
    pub max_us_per_mj_step: f64,
    /// Median time per 20 ms control step (5 substeps plus setting targets).
    pub median_us_per_control_step: f64,
    pub blocks: usize,
    pub steps_per_block: usize,
}

/// Flies the robot in a steady flapping motion (so the fluid model does real work) and times
/// `blocks` blocks of `steps_per_block` MuJoCo steps each.
pub fn time_steps(robot: &RobotModel, blocks: usize, steps_per_block: usize) -> Result<StepTiming, ModelError> {
    const SUBSTEPS: usize = 5;
    let mut sim = robot.instantiate()?;
    let start =
        InitialState { linear_velocity_mps: Vec3::new(crate::CRUISE_SPEED_MPS, 0.0, 0.0), ..InitialState::default() };
    let mut per_step_us = Vec::with_capacity(blocks);
    let mut per_control_us = Vec::with_capacity(blocks);
    for _ in 0..blocks.max(1) {
        sim.reset(&start);
        let control_steps = (steps_per_block / SUBSTEPS).max(1);
        let began = Instant::now();
        for k in 0..control_steps {
            let phase = k as f64 * 0.02 * 5.3 * std::f64::consts::TAU;
            let flap = 0.35 * phase.sin();
            sim.set_joint_targets(&[flap, 0.0, flap, 0.0, -0.17]);
            // A fault restarts the flight inside the block (a rare reset, timed with the steps).
            if sim.step(SUBSTEPS).is_err() {
                sim.reset(&start);
            }
        }
        let elapsed_us = began.elapsed().as_secs_f64() * 1e6;
        per_control_us.push(elapsed_us / control_steps as f64);
        per_step_us.push(elapsed_us / (control_steps * SUBSTEPS) as f64);
    }
    Ok(StepTiming {
        median_us_per_mj_step: median(&mut per_step_us.clone()),
        min_us_per_mj_step: per_step_us.iter().copied().fold(f64::INFINITY, f64::min),
        max_us_per_mj_step: per_step_us.iter().copied().fold(0.0, f64::max),
        median_us_per_control_step: median(&mut per_control_us),
        blocks: blocks.max(1),
        steps_per_block,
    })
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 { values[n / 2] } else { 0.5 * (values[n / 2 - 1] + values[n / 2]) }
}
