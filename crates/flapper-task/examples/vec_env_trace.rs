//! Steps a `FlightVecEnv` with given actions and writes what it returned, for checking another
//! front end (the Python binding's tests) against the Rust environments number for number.
//!
//! cargo run --release -p flapper-task --example vec_env_trace -- STAGE SEED ENVS THREADS ACTIONS OUT
//!
//! ACTIONS: little-endian f32, steps x ENVS x 5. OUT (a folder) gets little-endian files:
//! observations.f32 ((steps + 1) x ENVS x obs: after construction, then after each step),
//! rewards.f32 and position_errors.f32 (steps x ENVS), terminated.u8 and truncated.u8 (steps x ENVS).

use std::path::PathBuf;

use flapper_sim::RobotModel;
use flapper_task::{FlightVecEnv, ReferenceSource, TaskConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [stage, seed, envs, threads, actions, out] = args.as_slice() else {
        return Err("usage: vec_env_trace STAGE SEED ENVS THREADS ACTIONS OUT".into());
    };
    let (stage, seed, count, threads): (i64, u64, usize, usize) =
        (stage.parse()?, seed.parse()?, envs.parse()?, threads.parse()?);
    let actions: Vec<f32> =
        std::fs::read(actions)?.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    let mut envs = FlightVecEnv::new(
        &RobotModel::flapper()?,
        TaskConfig::stage(stage)?,
        ReferenceSource::Procedural,
        count,
        seed,
        threads,
    )?;
    let (mut observations, mut rewards, mut errors) = (envs.observations().to_vec(), Vec::new(), Vec::new());
    let (mut terminated, mut truncated) = (Vec::new(), Vec::new());
    for step_actions in actions.chunks_exact(count * 5) {
        envs.step(step_actions)?;
        observations.extend_from_slice(envs.observations());
        rewards.extend_from_slice(envs.rewards());
        errors.extend_from_slice(envs.position_errors_m());
        terminated.extend(envs.terminated().iter().map(|&t| u8::from(t)));
        truncated.extend(envs.truncated().iter().map(|&t| u8::from(t)));
    }
    let out = PathBuf::from(out);
    std::fs::create_dir_all(&out)?;
    let floats = |values: &[f32]| values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
    std::fs::write(out.join("observations.f32"), floats(&observations))?;
    std::fs::write(out.join("rewards.f32"), floats(&rewards))?;
    std::fs::write(out.join("position_errors.f32"), floats(&errors))?;
    std::fs::write(out.join("terminated.u8"), terminated)?;
    std::fs::write(out.join("truncated.u8"), truncated)?;
    Ok(())
}
