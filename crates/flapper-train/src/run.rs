//! Starting training runs: the flight task from a [`TrainConfig`], and the inverted-pendulum check
//! with its own small settings.

use std::path::{Path, PathBuf};

use flapper_ppo::evaluate::evaluate_mean_policy;
use flapper_ppo::{EndReason, PpoConfig, RunnerConfig, Start, TrainError, Trainer};
use flapper_sim::{ModelError, RobotModel};

use crate::config::{TrainConfig, TrainConfigError};
use crate::flight_envs::FlightEnvs;
use crate::inverted_pendulum::{InvertedPendulumEnvs, MAX_EPISODE_STEPS, PendulumEnd};

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Config(#[from] TrainConfigError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error(transparent)]
    Train(#[from] TrainError),
    #[error("cannot resume '{0}': it has no config.toml (was it made by `flapper train`?)")]
    NoRunConfig(PathBuf),
}

/// The config a run in `dir` was started with (for `--resume`).
pub fn saved_config(dir: &Path) -> Result<TrainConfig, RunError> {
    let path = dir.join("config.toml");
    if !path.exists() {
        return Err(RunError::NoRunConfig(dir.to_owned()));
    }
    Ok(TrainConfig::load(&path, None)?)
}

/// A trainer for the flight task in `dir`.
pub fn flight_trainer(
    robot: &RobotModel,
    config: &TrainConfig,
    dir: &Path,
    start: Start,
) -> Result<Trainer<FlightEnvs>, RunError> {
    let r = &config.runner;
    let envs = FlightEnvs::new(robot, config.task.clone(), r.envs, r.seed, r.thread_count())?;
    let mut trainer = Trainer::new(envs, config.ppo.clone(), r.clone(), config.to_toml(), dir, start)?;
    trainer.add_checkpoint_hook(crate::curves::learning_curves_hook());
    Ok(trainer)
}

/// Settings for the inverted pendulum: rsl_rl's PPO with smaller networks and fewer environments.
pub fn pendulum_settings(seed: u64, max_iterations: usize) -> (PpoConfig, RunnerConfig) {
    let ppo = PpoConfig { actor_hidden: vec![64, 64], critic_hidden: vec![64, 64], ..PpoConfig::default() };
    let runner = RunnerConfig {
        envs: 64,
        iterations: max_iterations,
        seed,
        threads: 1,
        checkpoint_every: 1000,
        init_from_noise_std: None,
    };
    (ppo, runner)
}

/// How a pendulum run went.
#[derive(Debug, Clone)]
pub struct PendulumOutcome {
    /// Environment steps when the mean policy first held the pole for 1000 steps in every one of
    /// `check_episodes` test episodes; `None` if it never did within the iterations.
    pub steps_to_solve: Option<u64>,
    pub iterations: usize,
    /// Returns of the last test of the mean policy.
    pub test_returns: Vec<f64>,
}

/// Trains on the inverted pendulum until the mean policy scores 1000 on `check_episodes` fresh test
/// episodes (tested whenever the last 10 training episodes all reached the time limit).
pub fn solve_inverted_pendulum(
    seed: u64,
    max_iterations: usize,
    check_episodes: usize,
    dir: &Path,
) -> Result<PendulumOutcome, RunError> {
    let (ppo, runner) = pendulum_settings(seed, max_iterations);
    let envs = InvertedPendulumEnvs::new(runner.envs, seed).map_err(TrainError::Env)?;
    let config_text = format!("# inverted pendulum check, seed {seed}\n");
    let mut trainer = Trainer::new(envs, ppo, runner, config_text, dir, Start::Fresh)?;
    trainer.add_checkpoint_hook(crate::curves::learning_curves_hook());
    let time_limit_column =
        PendulumEnd::ALL.iter().position(|r| *r == PendulumEnd::TimeLimit).expect("the pendulum reports time limits");
    let mut recent: Vec<f64> = Vec::new();
    let mut outcome = PendulumOutcome { steps_to_solve: None, iterations: 0, test_returns: Vec::new() };
    let mut test_error = None;
    trainer.run(&mut |log, policy| {
        outcome.iterations = log.iteration;
        // Returns of this iteration's finished episodes are all we see; keep the last 10.
        if log.episodes > 0 {
            let full = log.end_counts.get(time_limit_column).copied().unwrap_or(0);
            recent.extend(std::iter::repeat_n(MAX_EPISODE_STEPS as f64, full));
            recent.extend(std::iter::repeat_n(0.0, log.episodes - full));
            let excess = recent.len().saturating_sub(10);
            recent.drain(..excess);
        }
        if recent.len() == 10 && recent.iter().all(|&r| r == MAX_EPISODE_STEPS as f64) {
            let test = InvertedPendulumEnvs::new(check_episodes, seed ^ 0x7e57)
                .and_then(|mut env| evaluate_mean_policy(policy, &mut env, check_episodes, MAX_EPISODE_STEPS + 1));
            match test {
                Ok(episodes) => {
                    outcome.test_returns = episodes.iter().map(|e| e.episode_return).collect();
                    if episodes.len() == check_episodes
                        && episodes.iter().all(|e| e.episode_return >= MAX_EPISODE_STEPS as f64)
                    {
                        outcome.steps_to_solve = Some(log.env_steps);
                        return false;
                    }
                }
                Err(e) => {
                    test_error = Some(e);
                    return false;
                }
            }
        }
        true
    })?;
    if let Some(e) = test_error {
        return Err(TrainError::Env(e).into());
    }
    Ok(outcome)
}
