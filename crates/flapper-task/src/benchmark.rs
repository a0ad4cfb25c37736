//! Throughput of the vectorized environments: environment steps per second with fixed actions,
//! including observation building, reward, termination and automatic resets. Used by `flapper bench`.

use std::time::Instant;

use flapper_sim::{ModelError, RobotModel};

use crate::config::TaskConfig;
use crate::env::ReferenceSource;
use crate::vec_env::FlightVecEnv;

#[derive(Debug, Clone)]
pub struct EnvThroughput {
    pub envs: usize,
    pub threads: usize,
    /// Median over blocks of environment steps (control steps, all environments) per second.
    pub median_steps_per_s: f64,
    pub min_steps_per_s: f64,
    pub max_steps_per_s: f64,
    pub blocks: usize,
    pub steps_per_block: usize,
}

/// Times `blocks` blocks of `steps_per_block` vector steps of `envs` stage-1 environments, all
/// flapping with the same fixed open-loop action pattern.
pub fn time_vec_env(
    robot: &RobotModel,
    envs: usize,
    threads: usize,
    blocks: usize,
    steps_per_block: usize,
) -> Result<EnvThroughput, ModelError> {
    let mut vec_env = FlightVecEnv::new(robot, TaskConfig::default(), ReferenceSource::Procedural, envs, 0, threads)?;
    let mut rates = Vec::with_capacity(blocks);
    let mut step = 0usize;
    let mut actions = vec![0.0f32; envs * 5];
    for _ in 0..blocks.max(1) {
        let began = Instant::now();
        for _ in 0..steps_per_block {
            let flap = (step as f32 * 0.02 * 5.3 * std::f32::consts::TAU).sin() * 0.33;
            for action in actions.chunks_exact_mut(5) {
                action.copy_from_slice(&[flap, 0.0, flap, 0.0, -0.5]);
            }
            vec_env.step(&actions)?;
            vec_env.take_finished_episodes();
            step += 1;
        }
        rates.push((envs * steps_per_block) as f64 / began.elapsed().as_secs_f64());
    }
    let mut sorted = rates.clone();
    sorted.sort_by(f64::total_cmp);
    Ok(EnvThroughput {
        envs,
        threads: if threads == 0 { rayon::current_num_threads() } else { threads },
        median_steps_per_s: sorted[sorted.len() / 2],
        min_steps_per_s: sorted[0],
        max_steps_per_s: sorted[sorted.len() - 1],
        blocks: blocks.max(1),
        steps_per_block,
    })
}
