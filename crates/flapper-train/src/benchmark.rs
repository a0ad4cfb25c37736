//! End-to-end training throughput on the flight task: real PPO iterations (collect, infer, update)
//! with the run's default layout, timed per iteration and split into environment stepping,
//! inference and update. Used by `flapper bench`.

use flapper_ppo::Start;
use flapper_sim::RobotModel;

use crate::config::TrainConfig;
use crate::run::{RunError, flight_trainer};

#[derive(Debug, Clone)]
pub struct TrainingThroughput {
    pub envs: usize,
    pub threads: usize,
    pub iterations: usize,
    /// Median over iterations (the first, which allocates, left out).
    pub median_steps_per_s: f64,
    /// Shares of the timed work, summed over iterations.
    pub env_fraction: f64,
    pub inference_fraction: f64,
    pub update_fraction: f64,
}

/// Trains `iterations + 1` iterations of the default stage-1 run with `envs` environments on
/// `threads` threads (0 = all cores) in a scratch folder, which is removed afterwards.
pub fn time_training(
    robot: &RobotModel,
    envs: usize,
    threads: usize,
    iterations: usize,
) -> Result<TrainingThroughput, RunError> {
    let mut config = TrainConfig::from_toml("", "benchmark", None)?;
    config.runner.envs = envs;
    config.runner.threads = threads;
    config.runner.iterations = iterations + 1;
    config.runner.checkpoint_every = 1_000_000;
    let dir = std::env::temp_dir().join(format!("flapper-bench-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let result = (|| {
        let mut trainer = flight_trainer(robot, &config, &dir, Start::Fresh)?;
        trainer.run(&mut |_, _| true)?;
        Ok::<_, RunError>(trainer.history().to_vec())
    })();
    let _ = std::fs::remove_dir_all(&dir);
    let history = result?;
    let timed = &history[1..];
    let mut rates: Vec<f64> = timed.iter().map(|l| l.steps_per_s).collect();
    rates.sort_by(f64::total_cmp);
    let (env, inference, update) = timed
        .iter()
        .fold((0.0, 0.0, 0.0), |t, l| (t.0 + l.env_time_s, t.1 + l.inference_time_s, t.2 + l.update_time_s));
    let total = env + inference + update;
    Ok(TrainingThroughput {
        envs,
        threads: config.runner.thread_count(),
        iterations: timed.len(),
        median_steps_per_s: rates[rates.len() / 2],
        env_fraction: env / total,
        inference_fraction: inference / total,
        update_fraction: update / total,
    })
}
