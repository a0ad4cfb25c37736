//! The on-policy runner (rsl_rl's `OnPolicyRunner`): collect a rollout from the vectorized
//! environments, update, log one CSV row, save checkpoints and learning curves; start fresh, resume a
//! run, or start from another run's policy.
//!
//! Run folder: `config.toml` (the full config), `training.csv` (one row per iteration),
//! `learning_curves.svg`, `checkpoints/iter_NNNNNN.safetensors` (+ `.json`), and at the end
//! `policy.safetensors` (+ `.json`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::actor_critic::ActorCritic;
use crate::checkpoint::{self, CheckpointError};
use crate::config::{PpoConfig, RunnerConfig};
use crate::curves::write_learning_curves;
use crate::ppo::{Ppo, UpdateStats};
use crate::vec_env::{EnvError, VecEnv};

#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error("environment: {0}")]
    Env(EnvError),
    #[error("'{0}' already holds a training run; pass --resume to continue it or choose another --out")]
    RunExists(PathBuf),
    #[error("'{dir}' already holds {file}, which a new run would overwrite; give --out a new or empty folder (or move the file)")]
    WouldOverwrite { dir: PathBuf, file: &'static str },
    #[error("cannot resume: '{path}' {problem}; the checkpoints are intact: restore the file, or move it away to resume with a new log from the checkpoint on")]
    DamagedLog { path: PathBuf, problem: String },
    #[error("another flapper train is using '{0}' (its lock file .lock is held); wait for it to end or use another --out")]
    Busy(PathBuf),
    #[error("'{0}' has no checkpoint to resume from (checkpoints/iter_*.safetensors)")]
    NothingToResume(PathBuf),
    #[error("cannot write '{path}': {message}")]
    Output { path: PathBuf, message: String },
    #[error("'{0}' holds no environment state (written by an older flapper, whose runs restarted their environments at every checkpoint); start a new run with --init-from on it instead")]
    NoEnvironmentState(PathBuf),
    #[error("the run reached {iterations} iterations already (checkpoint at iteration {done}); raise the iteration count to train further")]
    AlreadyDone { iterations: usize, done: usize },
}

/// How a run begins.
#[derive(Debug, Clone)]
pub enum Start {
    /// New networks; the run folder must not hold a run yet.
    Fresh,
    /// Continue from the latest checkpoint in the run folder.
    Resume,
    /// New run whose policy (networks and normalizer) starts as another run's (curriculum stages).
    InitFrom(PathBuf),
}

/// One iteration's figures: one CSV row.
#[derive(Debug, Clone, PartialEq)]
pub struct IterationLog {
    /// Iterations completed (1 after the first).
    pub iteration: usize,
    pub env_steps: u64,
    pub wall_time_s: f64,
    /// Environment steps per second over this iteration.
    pub steps_per_s: f64,
    /// Episodes finished in this iteration, their mean return and length, and how they ended
    /// (counts in the order of `VecEnv::end_reasons`).
    pub episodes: usize,
    pub mean_return: f64,
    pub mean_length: f64,
    pub end_counts: Vec<usize>,
    /// Mean reward per step and mean of each environment diagnostic over the rollout.
    pub mean_reward: f64,
    pub diagnostics: Vec<f64>,
    pub update: UpdateStats,
    pub env_time_s: f64,
    pub inference_time_s: f64,
    pub update_time_s: f64,
}

pub struct Trainer<E: VecEnv> {
    env: E,
    ppo: Ppo,
    runner: RunnerConfig,
    config_toml: String,
    dir: PathBuf,
    iteration: usize,
    env_steps: u64,
    wall_time_before_s: f64,
    history: Vec<IterationLog>,
    end_reasons: Vec<&'static str>,
    diagnostic_names: Vec<String>,
    /// Held while the run lives, so that no second trainer writes into the same folder.
    _run_lock: std::fs::File,
}

/// Takes the run folder's lock (`dir/.lock`, released by the OS when the process ends).
fn lock_run(dir: &Path) -> Result<std::fs::File, TrainError> {
    let path = dir.join(".lock");
    let file = std::fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(&path)
        .map_err(|e| TrainError::Output { path: path.clone(), message: e.to_string() })?;
    match file.try_lock() {
        Ok(()) => Ok(file),
        Err(std::fs::TryLockError::WouldBlock) => Err(TrainError::Busy(dir.to_owned())),
        Err(std::fs::TryLockError::Error(e)) => Err(TrainError::Output { path, message: e.to_string() }),
    }
}

/// The files a run writes in its folder besides the checkpoints: a new run refuses a
/// folder that holds any of them, so it never overwrites a user's own file.
pub const RUN_FILES: [&str; 5] = ["config.toml", "policy.safetensors", "policy.safetensors.json", "learning_curves.svg", "training.csv"];

pub fn checkpoint_dir(dir: &Path) -> PathBuf {
    dir.join("checkpoints")
}

/// The newest `iter_NNNNNN.safetensors` in the run's checkpoint folder.
pub fn latest_checkpoint(dir: &Path) -> Option<PathBuf> {
    let entries = std::fs::read_dir(checkpoint_dir(dir)).ok()?;
    entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?;
            let number: usize = name.strip_prefix("iter_")?.strip_suffix(".safetensors")?.parse().ok()?;
            Some((number, p))
        })
        .max_by_key(|(n, _)| *n)
        .map(|(_, p)| p)
}

impl<E: VecEnv> Trainer<E> {
    /// Prepares a run in `dir`. For `Start::Resume` the caller passes the config the run was started
    /// with (`config.toml` in the folder; `runner.iterations` may be raised).
    pub fn new(
        mut env: E,
        ppo_config: PpoConfig,
        runner: RunnerConfig,
        config_toml: String,
        dir: &Path,
        start: Start,
    ) -> Result<Self, TrainError> {
        let threads = runner.thread_count();
        let (o, a) = (env.observation_size(), env.action_size());
        let mut rng = ChaCha8Rng::seed_from_u64(runner.seed);
        let output = |path: &Path, e: &dyn std::fmt::Display| TrainError::Output { path: path.to_owned(), message: e.to_string() };
        let (mut iteration, mut env_steps, mut wall_time_before_s) = (0, 0, 0.0);
        let run_lock: std::fs::File;
        let ppo = match &start {
            Start::Fresh | Start::InitFrom(_) => {
                if latest_checkpoint(dir).is_some() || dir.join("training.csv").exists() {
                    return Err(TrainError::RunExists(dir.to_owned()));
                }
                if let Some(file) = RUN_FILES.into_iter().find(|file| dir.join(file).exists()) {
                    return Err(TrainError::WouldOverwrite { dir: dir.to_owned(), file });
                }
                let loaded = match &start {
                    Start::InitFrom(path) => {
                        let loaded = checkpoint::load(path)?;
                        loaded.check_layout(path, o, a)?;
                        Some(loaded)
                    }
                    _ => None,
                };
                std::fs::create_dir_all(checkpoint_dir(dir)).map_err(|e| output(dir, &e))?;
                run_lock = lock_run(dir)?;
                // Again under the lock: another trainer may have started here since the check above
                // (which keeps a refused start from creating the folder and its lock file).
                if dir.join("training.csv").exists() {
                    return Err(TrainError::RunExists(dir.to_owned()));
                }
                checkpoint::write_atomically(&dir.join("config.toml"), config_toml.as_bytes())?;
                match loaded {
                    Some(loaded) => {
                        // A trained policy is sharp (small action noise): a fresh Adam at the
                        // initial step size moves it far in the first update (the stage-2 run saw a
                        // KL of 75). Continue at the step size the source run ended with, and with
                        // its Adam moments when the file is a checkpoint that holds them.
                        let mut ppo = Ppo::new(loaded.policy, ppo_config, runner.envs, rng, threads);
                        if ppo.config.schedule == crate::config::Schedule::Adaptive {
                            ppo.learning_rate = loaded.info.learning_rate;
                        }
                        if let Some(optimizer) = loaded.optimizer {
                            ppo.optimizer = optimizer;
                        }
                        if let Some(std) = runner.init_from_noise_std {
                            ppo.policy.log_std.iter_mut().for_each(|s| *s = std.ln());
                        }
                        ppo
                    }
                    None => Ppo::new(ActorCritic::new(o, a, &ppo_config, &mut rng), ppo_config, runner.envs, rng, threads),
                }
            }
            Start::Resume => {
                let path = latest_checkpoint(dir).ok_or_else(|| TrainError::NothingToResume(dir.to_owned()))?;
                run_lock = lock_run(dir)?;
                let loaded = checkpoint::load(&path)?;
                loaded.check_layout(&path, o, a)?;
                let rng = loaded.rng().expect("load() checked the random state");
                let optimizer = loaded.optimizer.clone().expect("checkpoints hold the optimizer");
                if loaded.info.iteration >= runner.iterations {
                    return Err(TrainError::AlreadyDone { iterations: runner.iterations, done: loaded.info.iteration });
                }
                let environments = loaded.environments.as_deref().ok_or_else(|| TrainError::NoEnvironmentState(path.clone()))?;
                env.restore_state(environments).map_err(TrainError::Env)?;
                iteration = loaded.info.iteration;
                env_steps = loaded.info.env_steps;
                wall_time_before_s = loaded.info.wall_time_s;
                let mut ppo = Ppo::new(loaded.policy, ppo_config, runner.envs, rng, threads);
                ppo.optimizer = optimizer;
                ppo.learning_rate = loaded.info.learning_rate;
                ppo
            }
        };
        let end_reasons = env.end_reasons();
        let diagnostic_names = env.diagnostic_names();
        let mut trainer = Self {
            env,
            ppo,
            runner,
            config_toml,
            dir: dir.to_owned(),
            iteration,
            env_steps,
            wall_time_before_s,
            history: Vec::new(),
            end_reasons,
            diagnostic_names,
            _run_lock: run_lock,
        };
        trainer.prepare_csv(matches!(start, Start::Resume))?;
        Ok(trainer)
    }

    pub fn iteration(&self) -> usize {
        self.iteration
    }

    pub fn env_steps(&self) -> u64 {
        self.env_steps
    }

    pub fn ppo(&self) -> &Ppo {
        &self.ppo
    }

    pub fn env(&self) -> &E {
        &self.env
    }

    pub fn history(&self) -> &[IterationLog] {
        &self.history
    }

    pub fn csv_path(&self) -> PathBuf {
        self.dir.join("training.csv")
    }

    pub fn end_reasons(&self) -> &[&'static str] {
        &self.end_reasons
    }

    /// Trains to `runner.iterations`, calling `on_iteration` after each; it returns false to stop
    /// early. Saves a checkpoint every `checkpoint_every` iterations and at the end, then the final
    /// policy (`policy.safetensors`).
    pub fn run(&mut self, on_iteration: &mut dyn FnMut(&IterationLog, &ActorCritic) -> bool) -> Result<(), TrainError> {
        let (envs, a) = (self.env.num_envs(), self.env.action_size());
        let mut actions = vec![0.0f32; envs * a];
        let steps = self.ppo.config.steps_per_env;
        let n_diag = self.diagnostic_names.len();
        let session_start = Instant::now();
        while self.iteration < self.runner.iterations {
            let began = Instant::now();
            let (mut env_time, mut inference_time) = (0.0, 0.0);
            let mut reward_sum = 0.0f64;
            let mut diagnostic_sums = vec![0.0f64; n_diag];
            let mut episodes = Vec::new();
            for _ in 0..steps {
                let t = Instant::now();
                self.ppo.act(self.env.observations(), &mut actions);
                let t_env = Instant::now();
                inference_time += (t_env - t).as_secs_f64();
                self.env.step(&actions).map_err(TrainError::Env)?;
                let t_after = Instant::now();
                env_time += (t_after - t_env).as_secs_f64();
                let e = &self.env;
                self.ppo.process_step(e.rewards(), e.terminated(), e.truncated(), e.final_observations());
                inference_time += t_after.elapsed().as_secs_f64();
                reward_sum += e.rewards().iter().map(|&r| r as f64).sum::<f64>();
                for (k, &v) in e.diagnostics().iter().enumerate() {
                    diagnostic_sums[k % n_diag] += v as f64;
                }
                episodes.extend(self.env.take_finished_episodes());
            }
            let t = Instant::now();
            self.ppo.finish_rollout(self.env.observations());
            inference_time += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let update = self.ppo.update();
            let update_time = t.elapsed().as_secs_f64();

            self.iteration += 1;
            let collected = (envs * steps) as u64;
            self.env_steps += collected;
            let samples = (envs * steps) as f64;
            let count = episodes.len();
            let mean = |f: &dyn Fn(&crate::vec_env::EpisodeRecord) -> f64| {
                if count == 0 { f64::NAN } else { episodes.iter().map(f).sum::<f64>() / count as f64 }
            };
            let log = IterationLog {
                iteration: self.iteration,
                env_steps: self.env_steps,
                wall_time_s: self.wall_time_before_s + session_start.elapsed().as_secs_f64(),
                steps_per_s: collected as f64 / began.elapsed().as_secs_f64(),
                episodes: count,
                mean_return: mean(&|e| e.episode_return),
                mean_length: mean(&|e| e.length as f64),
                end_counts: self.end_reasons.iter().map(|r| episodes.iter().filter(|e| e.end_reason == *r).count()).collect(),
                mean_reward: reward_sum / samples,
                diagnostics: diagnostic_sums.iter().map(|s| s / samples).collect(),
                update,
                env_time_s: env_time,
                inference_time_s: inference_time,
                update_time_s: update_time,
            };
            self.append_csv(&log)?;
            self.history.push(log.clone());
            let last = !on_iteration(&log, &self.ppo.policy) || self.iteration == self.runner.iterations;
            if self.iteration.is_multiple_of(self.runner.checkpoint_every) || last {
                self.save_checkpoint(log.wall_time_s)?;
                self.write_curves()?;
            }
            if last {
                let path = self.dir.join("policy.safetensors");
                let info = checkpoint::describe(&self.ppo, "policy", self.iteration, self.env_steps, log.wall_time_s, &self.config_toml);
                checkpoint::save(&path, &info, &self.ppo.policy, None, None)?;
                break;
            }
        }
        Ok(())
    }

    fn save_checkpoint(&self, wall_time_s: f64) -> Result<(), TrainError> {
        let path = checkpoint_dir(&self.dir).join(format!("iter_{:06}.safetensors", self.iteration));
        let info = checkpoint::describe(&self.ppo, "checkpoint", self.iteration, self.env_steps, wall_time_s, &self.config_toml);
        let environments = self.env.save_state().map_err(TrainError::Env)?;
        checkpoint::save(&path, &info, &self.ppo.policy, Some(&self.ppo.optimizer), Some(&environments))?;
        Ok(())
    }

    fn write_curves(&self) -> Result<(), TrainError> {
        let path = self.dir.join("learning_curves.svg");
        let rows = read_history(&self.csv_path()).unwrap_or_else(|_| self.history.clone());
        write_learning_curves(&rows, &self.end_reasons, &path).map_err(|e| TrainError::Output { path, message: e })
    }

    fn header(&self) -> Vec<String> {
        let mut h: Vec<String> = [
            "iteration", "env_steps", "wall_time_s", "steps_per_s", "episodes", "mean_return", "mean_length",
        ]
        .map(String::from)
        .to_vec();
        h.extend(self.end_reasons.iter().map(|r| format!("end_{r}")));
        h.push("mean_reward".into());
        h.extend(self.diagnostic_names.iter().cloned());
        h.extend(
            [
                "surrogate_loss", "value_loss", "entropy", "kl", "clip_fraction", "grad_norm", "learning_rate", "action_std",
                "env_time_s", "inference_time_s", "update_time_s",
            ]
            .map(String::from),
        );
        h
    }

    /// A fresh run writes the header; a resumed one keeps the rows up to its checkpoint (a killed run
    /// may have logged iterations past its last checkpoint, which the resumed run repeats).
    fn prepare_csv(&mut self, resume: bool) -> Result<(), TrainError> {
        let path = self.csv_path();
        let header = self.header().join(",");
        let mut text = header.clone() + "\n";
        if resume && path.exists() {
            // Read strictly: a damaged log is refused, never silently shortened.
            let damaged = |problem: String| TrainError::DamagedLog { path: path.clone(), problem };
            let bytes = std::fs::read(&path).map_err(|e| damaged(format!("cannot be read ({e})")))?;
            let existing = String::from_utf8(bytes)
                .map_err(|e| damaged(format!("is not text (invalid UTF-8 at byte {})", e.utf8_error().valid_up_to())))?;
            for (number, line) in existing.lines().enumerate().skip(1) {
                let Some(iteration) = line.split(',').next().and_then(|v| v.parse::<usize>().ok()) else {
                    return Err(damaged(format!("line {} does not start with an iteration number", number + 1)));
                };
                if iteration <= self.iteration {
                    text.push_str(line);
                    text.push('\n');
                }
            }
        }
        checkpoint::write_atomically(&path, text.as_bytes())?;
        Ok(())
    }

    fn append_csv(&self, log: &IterationLog) -> Result<(), TrainError> {
        use std::io::Write;
        let path = self.csv_path();
        let u = &log.update;
        let mut fields: Vec<String> = vec![
            log.iteration.to_string(),
            log.env_steps.to_string(),
            format!("{:.3}", log.wall_time_s),
            format!("{:.1}", log.steps_per_s),
            log.episodes.to_string(),
            format!("{:.6}", log.mean_return),
            format!("{:.3}", log.mean_length),
        ];
        fields.extend(log.end_counts.iter().map(|c| c.to_string()));
        fields.push(format!("{:.6}", log.mean_reward));
        fields.extend(log.diagnostics.iter().map(|d| format!("{d:.6}")));
        for v in [u.surrogate_loss, u.value_loss, u.entropy, u.kl, u.clip_fraction, u.grad_norm, u.learning_rate, u.action_std] {
            fields.push(format!("{v:.9}"));
        }
        for v in [log.env_time_s, log.inference_time_s, log.update_time_s] {
            fields.push(format!("{v:.4}"));
        }
        let mut file = std::fs::OpenOptions::new()
            .append(true)
            .open(&path)
            .map_err(|e| TrainError::Output { path: path.clone(), message: e.to_string() })?;
        writeln!(file, "{}", fields.join(",")).map_err(|e| TrainError::Output { path, message: e.to_string() })
    }
}

/// Reads the plotted columns of a training CSV back (for learning curves over resumed runs).
pub fn read_history(path: &Path) -> Result<Vec<IterationLog>, String> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| e.to_string())?;
    let headers = reader.headers().map_err(|e| e.to_string())?.clone();
    let column = |name: &str| headers.iter().position(|h| h == name);
    let ends: Vec<usize> = headers.iter().enumerate().filter(|(_, h)| h.starts_with("end_")).map(|(i, _)| i).collect();
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| e.to_string())?;
        let get = |name: &str| column(name).and_then(|i| record.get(i)).and_then(|v| v.parse::<f64>().ok()).unwrap_or(f64::NAN);
        rows.push(IterationLog {
            iteration: get("iteration") as usize,
            env_steps: get("env_steps") as u64,
            wall_time_s: get("wall_time_s"),
            steps_per_s: get("steps_per_s"),
            episodes: get("episodes") as usize,
            mean_return: get("mean_return"),
            mean_length: get("mean_length"),
            end_counts: ends.iter().map(|&i| record.get(i).and_then(|v| v.parse().ok()).unwrap_or(0)).collect(),
            mean_reward: get("mean_reward"),
            diagnostics: Vec::new(),
            update: UpdateStats {
                surrogate_loss: get("surrogate_loss"),
                value_loss: get("value_loss"),
                entropy: get("entropy"),
                kl: get("kl"),
                clip_fraction: get("clip_fraction"),
                grad_norm: get("grad_norm"),
                learning_rate: get("learning_rate"),
                action_std: get("action_std"),
            },
            env_time_s: get("env_time_s"),
            inference_time_s: get("inference_time_s"),
            update_time_s: get("update_time_s"),
        });
    }
    Ok(rows)
}
