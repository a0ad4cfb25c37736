//! `flapper train` and `flapper pendulum`: read the options, start or resume the run, show progress.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, bail};
use flapper_ppo::{IterationLog, Start, TrainError};
use flapper_sim::RobotModel;
use flapper_train::TrainConfig;
use flapper_train::run::{RunError, flight_trainer, saved_config, solve_inverted_pendulum};
use indicatif::{ProgressBar, ProgressStyle};

use crate::flag_values::{count, seed};

/// Command-line values that replace the config's.
pub struct Overrides {
    pub iterations: Option<usize>,
    pub seed: Option<u64>,
    pub envs: Option<usize>,
}

pub fn train_command(
    robot: &RobotModel,
    config_path: Option<&Path>,
    stage: Option<i64>,
    out: &Path,
    resume: bool,
    init_from: Option<PathBuf>,
    overrides: Overrides,
) -> Result<()> {
    let mut config = if resume {
        saved_config(out)?
    } else {
        match config_path {
            Some(path) => TrainConfig::load(path, stage)?,
            None => TrainConfig::from_toml("", "defaults", stage)?,
        }
    };
    if resume {
        // A resumed run continues its own environments (clap already refuses --seed with --resume).
        if let Some(n) = overrides.envs.filter(|n| *n != config.runner.envs) {
            bail!(
                "--envs {n} with --resume: the run in '{}' has {} environments (a resumed run keeps them; start a new run with --init-from to change it)",
                out.display(),
                config.runner.envs
            );
        }
    }
    if let Some(n) = overrides.iterations {
        config.runner.iterations = n;
    }
    if let Some(s) = overrides.seed {
        config.runner.seed = s;
    }
    if let Some(n) = overrides.envs {
        config.runner.envs = n;
    }
    config.runner.validate(&config.ppo).context("command-line value")?;
    if let Some(path) = &init_from
        && !path.is_file()
    {
        bail!("--init-from '{}' is not a file", path.display());
    }
    let start = match (resume, init_from) {
        (true, _) => Start::Resume,
        (false, Some(path)) => Start::InitFrom(path),
        (false, None) => Start::Fresh,
    };
    let mut trainer = flight_trainer(robot, &config, out, start).map_err(with_flag_hint)?;
    let total = config.runner.iterations as u64;
    let samples = (config.runner.envs * config.ppo.steps_per_env) as u64;
    let ends = trainer.end_reasons().to_vec();
    println!(
        "training stage {} in {}: {} environments x {} steps per iteration, iterations {}..{}, seed {}, {} threads",
        config.task.stage,
        out.display(),
        config.runner.envs,
        config.ppo.steps_per_env,
        trainer.iteration(),
        total,
        config.runner.seed,
        config.runner.thread_count()
    );
    let bar = ProgressBar::new(total).with_position(trainer.iteration() as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} it  {elapsed_precise} ETA {eta_precise}  {msg}")
            .expect("a valid template"),
    );
    let interactive = std::io::stderr().is_terminal();
    if interactive {
        bar.enable_steady_tick(Duration::from_millis(500));
    } else {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    // Return and length smoothed over the last iterations' episodes (few episodes end per iteration).
    let mut recent: Vec<(f64, f64, usize)> = Vec::new();
    trainer.run(&mut |log: &IterationLog, _| {
        recent.push((log.mean_return * log.episodes as f64, log.mean_length * log.episodes as f64, log.episodes));
        if recent.len() > 20 {
            recent.remove(0);
        }
        let episodes: usize = recent.iter().map(|r| r.2).sum();
        let mean = |f: fn(&(f64, f64, usize)) -> f64| {
            if episodes == 0 {
                f64::NAN
            } else {
                recent.iter().filter(|r| r.2 > 0).map(f).sum::<f64>() / episodes as f64
            }
        };
        let ending: Vec<String> =
            ends.iter().zip(&log.end_counts).filter(|(_, c)| **c > 0).map(|(r, c)| format!("{r} {c}")).collect();
        let message = format!(
            "{:.2}M steps  {:.0} steps/s  return {}  length {}  std {:.2}  ends: {}",
            log.env_steps as f64 / 1e6,
            log.steps_per_s,
            crate::progress::episode_mean(mean(|r| r.0), 1),
            crate::progress::episode_mean(mean(|r| r.1), 0),
            log.update.action_std,
            if ending.is_empty() { "-".into() } else { ending.join(", ") }
        );
        bar.set_position(log.iteration as u64);
        if interactive {
            bar.set_message(message);
        } else if log.iteration.is_multiple_of(10) || log.iteration as u64 == total {
            eprintln!("it {}/{} {}", log.iteration, total, message);
        }
        true
    })?;
    bar.finish_and_clear();
    print_session_summary(trainer.iteration(), trainer.env_steps(), trainer.history(), samples);
    for file in ["policy.safetensors", "training.csv", "learning_curves.svg"] {
        println!("wrote {}", out.join(file).display());
    }
    Ok(())
}

/// What this session trained: iterations, steps, wall time, and where the time went.
fn print_session_summary(iteration: usize, env_steps: u64, history: &[IterationLog], samples: u64) {
    let last = history.last();
    println!(
        "done: {} iterations, {} environment steps{}",
        iteration,
        env_steps,
        last.map_or(String::new(), |l| format!(", {:.0} s training wall time", l.wall_time_s))
    );
    let timing: (f64, f64, f64) = history
        .iter()
        .fold((0.0, 0.0, 0.0), |t, l| (t.0 + l.env_time_s, t.1 + l.inference_time_s, t.2 + l.update_time_s));
    let sum = timing.0 + timing.1 + timing.2;
    if sum > 0.0 {
        let steps = history.len() as f64 * samples as f64;
        println!(
            "  this session: {:.0} environment steps/s; time in environments {:.0}%, inference {:.0}%, update {:.0}%",
            steps / sum,
            100.0 * timing.0 / sum,
            100.0 * timing.1 / sum,
            100.0 * timing.2 / sum
        );
    }
}

pub fn pendulum_command(seeds: &[u64], max_iterations: usize, out: &Path) -> Result<()> {
    if seeds.is_empty() || max_iterations == 0 {
        bail!("give at least one --seeds value and --max-iterations above 0");
    }
    println!(
        "inverted pendulum: 64 environments x 24 steps per iteration, solved = mean policy scores 1000 in 5 of 5 test episodes"
    );
    let mut solved = Vec::new();
    for &seed in seeds {
        let dir = out.join(format!("seed_{seed}"));
        if dir.exists() {
            std::fs::remove_dir_all(&dir).with_context(|| format!("cannot replace '{}'", dir.display()))?;
        }
        let began = std::time::Instant::now();
        let outcome = solve_inverted_pendulum(seed, max_iterations, 5, &dir)?;
        match outcome.steps_to_solve {
            Some(steps) => {
                println!(
                    "  seed {seed}: solved after {steps} environment steps ({} iterations, {:.1} s)",
                    outcome.iterations,
                    began.elapsed().as_secs_f64()
                );
                solved.push(steps);
            }
            None => println!(
                "  seed {seed}: not solved in {max_iterations} iterations (last test returns {:?})",
                outcome.test_returns
            ),
        }
    }
    solved.sort_unstable();
    if !solved.is_empty() {
        println!(
            "solved {}/{} seeds; steps to solve: median {}, min {}, max {}",
            solved.len(),
            seeds.len(),
            solved[solved.len() / 2],
            solved[0],
            solved[solved.len() - 1]
        );
    }
    println!("runs (CSV, learning curves, policies) in {}", out.display());
    Ok(())
}

/// `flapper train`'s options.
#[derive(clap::Args)]
pub struct TrainArgs {
    /// Run configuration (TOML with [runner], [ppo] and [task] tables; every key optional).
    #[arg(long, value_name = "TOML")]
    pub config: Option<PathBuf>,
    /// Curriculum stage 1-4 (replaces the config's task.stage).
    #[arg(long, value_parser = 1..=4, allow_negative_numbers = true)]
    pub stage: Option<i64>,
    /// Run folder (created; must not hold a run unless --resume).
    #[arg(long)]
    pub out: PathBuf,
    /// Continue the run in --out from its latest checkpoint, with the config it started with.
    #[arg(long, conflicts_with_all = ["config", "stage", "init_from", "seed"])]
    pub resume: bool,
    /// Start from this policy or checkpoint (e.g. the previous stage's policy.safetensors).
    #[arg(long, value_name = "FILE")]
    pub init_from: Option<PathBuf>,
    /// Number of PPO iterations (replaces runner.iterations; with --resume, raises the target).
    #[arg(long, value_parser = count, allow_negative_numbers = true)]
    pub iterations: Option<usize>,
    /// Random seed (replaces runner.seed).
    #[arg(long, value_parser = seed, allow_negative_numbers = true)]
    pub seed: Option<u64>,
    /// Parallel environments (replaces runner.envs).
    #[arg(long, value_parser = count, allow_negative_numbers = true)]
    pub envs: Option<usize>,
}

pub fn run(args: TrainArgs, model: Option<&Path>) -> Result<()> {
    let overrides = Overrides { iterations: args.iterations, seed: args.seed, envs: args.envs };
    let robot = crate::robot::load(model)?;
    train_command(&robot, args.config.as_deref(), args.stage, &args.out, args.resume, args.init_from, overrides)
}

/// The learner's errors describe the problem; here they also name the flag that answers it.
fn with_flag_hint(error: RunError) -> anyhow::Error {
    let hint = match &error {
        RunError::Train(TrainError::RunExists(_)) => "pass --resume to continue it, or choose another --out",
        RunError::Train(TrainError::Busy(_)) => "or pass another --out",
        RunError::Train(TrainError::NoEnvironmentState(_)) => "pass it to --init-from of a new run",
        RunError::Train(TrainError::AlreadyDone { .. }) => "pass a larger --iterations with --resume",
        _ => return error.into(),
    };
    anyhow::anyhow!("{error} ({hint})")
}
