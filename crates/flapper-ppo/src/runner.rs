//! The on-policy runner (rsl_rl's `OnPolicyRunner`): collect a rollout from the vectorized
//! environments, update, log one CSV row (`training_log`), save checkpoints and call the checkpoint
//! hooks (the training crate draws learning curves there); start fresh, resume a run, or start from
//! another run's policy. The folder it writes is `run_folder`'s.

use std::path::{Path, PathBuf};
use std::time::Instant;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::actor_critic::ActorCritic;
use crate::checkpoint::{self, CheckpointKind};
use crate::config::{PpoConfig, RunnerConfig};
use crate::ppo::Ppo;
use crate::run_folder::RunFolder;
use crate::training_log;
use crate::vec_env::{EndReason, VecEnv};

// The runner's errors and its per-iteration log, where the crate's root re-exports them from.
pub use crate::train_error::TrainError;
pub use crate::training_log::IterationLog;

/// How a run begins.
#[derive(Debug, Clone)]
pub enum Start {
    /// New networks; the run folder must not hold a run yet.
    Fresh,
    /// Continue from the latest checkpoint in the run folder.
    Resume,
    /// New run whose policy (networks and normalizer) starts as another run's (curriculum stages).
    InitFrom(PathBuf),
    /// Continue from the latest checkpoint as `Resume` does, with the action noise (standard deviation)
    /// reset to `noise_std`: fresh exploration for a curriculum stage whose learning has stalled. With
    /// `learner_from`, an earlier checkpoint of the same run (its best), the learner (networks,
    /// normalizer, optimizer, random state) goes back to that checkpoint's while the iteration count,
    /// the environment steps and the environments go on from the latest: the run goes on, its policy
    /// goes back to where it flew best.
    Restart { noise_std: f32, learner_from: Option<PathBuf> },
}

pub struct Trainer<E: VecEnv> {
    env: E,
    ppo: Ppo,
    runner: RunnerConfig,
    config_toml: String,
    /// The run's folder, locked while the trainer lives so that no second trainer writes into it.
    folder: RunFolder,
    iteration: usize,
    env_steps: u64,
    wall_time_before_s: f64,
    history: Vec<IterationLog>,
    end_reasons: Vec<&'static str>,
    diagnostic_names: Vec<String>,
    checkpoint_hooks: Vec<CheckpointHook>,
}

/// What a checkpoint hook sees: the run folder (its `training.csv` is complete up to `iteration`),
/// this session's iterations, and the names of the episode-end columns.
pub struct CheckpointEvent<'a> {
    pub dir: &'a Path,
    pub iteration: usize,
    pub history: &'a [IterationLog],
    pub end_reasons: &'a [&'static str],
}

/// Called after each checkpoint is saved (e.g. to draw learning curves: the learner draws nothing).
pub type CheckpointHook = Box<dyn FnMut(&CheckpointEvent) -> Result<(), String> + Send>;

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
        let (o, a) = (env.observation_size(), env.action_size());
        let mut progress = Progress::default();
        let (folder, ppo) = match &start {
            Start::Fresh => {
                let folder = RunFolder::create(dir, &config_toml)?;
                let mut rng = ChaCha8Rng::seed_from_u64(runner.seed);
                let policy = ActorCritic::new(o, a, &ppo_config, &mut rng);
                (folder, Ppo::new(policy, ppo_config, runner.envs, rng, runner.thread_count()))
            }
            Start::InitFrom(source) => {
                // The source is checked before the folder is made, so that a refused start leaves nothing.
                RunFolder::check_new(dir)?;
                let mut loaded = checkpoint::load(source)?;
                let extra = env.appendable_inputs();
                if extra > 0 && loaded.info.observation_size + extra == o {
                    loaded = loaded.with_inputs_appended(extra);
                }
                loaded.check_layout(source, o, a)?;
                let folder = RunFolder::create(dir, &config_toml)?;
                (folder, learner_from(loaded, ppo_config, &runner))
            }
            Start::Resume | Start::Restart { .. } => {
                let (folder, newest) = RunFolder::open(dir)?;
                let loaded = checkpoint::load(&newest)?;
                loaded.check_layout(&newest, o, a)?;
                if loaded.info.iteration >= runner.iterations {
                    return Err(TrainError::AlreadyDone { iterations: runner.iterations, done: loaded.info.iteration });
                }
                let environments =
                    loaded.environments.as_deref().ok_or_else(|| TrainError::NoEnvironmentState(newest.clone()))?;
                env.restore_state(environments).map_err(TrainError::Env)?;
                progress = Progress {
                    iteration: loaded.info.iteration,
                    env_steps: loaded.info.env_steps,
                    wall_time_s: loaded.info.wall_time_s,
                };
                let mut ppo = match &start {
                    Start::Restart { learner_from: Some(earlier), .. } => {
                        let earlier_loaded = checkpoint::load(earlier)?;
                        earlier_loaded.check_layout(earlier, o, a)?;
                        resumed_learner(earlier_loaded, ppo_config, &runner)
                    }
                    _ => resumed_learner(loaded, ppo_config, &runner),
                };
                if let Start::Restart { noise_std, .. } = start {
                    ppo.policy.set_noise_std(noise_std);
                }
                (folder, ppo)
            }
        };
        let end_reasons = E::EndReason::ALL.iter().map(|r| r.name()).collect();
        let diagnostic_names = env.diagnostic_names();
        let trainer = Self {
            env,
            ppo,
            runner,
            config_toml,
            folder,
            iteration: progress.iteration,
            env_steps: progress.env_steps,
            wall_time_before_s: progress.wall_time_s,
            history: Vec::new(),
            end_reasons,
            diagnostic_names,
            checkpoint_hooks: Vec::new(),
        };
        let config = &trainer.ppo.config;
        let (smoothness, curvature) = (config.smoothness_coef > 0.0, config.curvature_coef > 0.0);
        let header = training_log::header(&trainer.end_reasons, &trainer.diagnostic_names, smoothness, curvature);
        training_log::prepare(
            &trainer.csv_path(),
            &header,
            matches!(start, Start::Resume | Start::Restart { .. }),
            trainer.iteration,
        )?;
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
        self.folder.training_csv()
    }

    pub fn end_reasons(&self) -> &[&'static str] {
        &self.end_reasons
    }

    /// Adds a hook run after every checkpoint (and the final one).
    pub fn add_checkpoint_hook(&mut self, hook: CheckpointHook) {
        self.checkpoint_hooks.push(hook);
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
                if let Some(weights) = self.env.smoothness_weights() {
                    self.ppo.weigh_smoothness(weights);
                }
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
            let mean = |f: &dyn Fn(&crate::vec_env::EpisodeRecord<E::EndReason>) -> f64| {
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
                end_counts: E::EndReason::ALL.iter().map(|r| episodes.iter().filter(|e| e.end == *r).count()).collect(),
                mean_reward: reward_sum / samples,
                diagnostics: diagnostic_sums.iter().map(|s| s / samples).collect(),
                update,
                env_time_s: env_time,
                inference_time_s: inference_time,
                update_time_s: update_time,
            };
            training_log::append(&self.csv_path(), &log)?;
            self.history.push(log.clone());
            let last = !on_iteration(&log, &self.ppo.policy) || self.iteration == self.runner.iterations;
            if self.iteration.is_multiple_of(self.runner.checkpoint_every) || last {
                self.save_checkpoint(log.wall_time_s)?;
                self.run_checkpoint_hooks()?;
            }
            if last {
                let path = self.folder.policy();
                let info = checkpoint::describe(
                    &self.ppo,
                    CheckpointKind::Policy,
                    self.iteration,
                    self.env_steps,
                    log.wall_time_s,
                    &self.config_toml,
                );
                checkpoint::save(&path, &info, &self.ppo.policy, None, None)?;
                break;
            }
        }
        Ok(())
    }

    fn save_checkpoint(&self, wall_time_s: f64) -> Result<(), TrainError> {
        let path = self.folder.checkpoint(self.iteration);
        let info = checkpoint::describe(
            &self.ppo,
            CheckpointKind::Checkpoint,
            self.iteration,
            self.env_steps,
            wall_time_s,
            &self.config_toml,
        );
        let environments = self.env.save_state().map_err(TrainError::Env)?;
        checkpoint::save(&path, &info, &self.ppo.policy, Some(&self.ppo.optimizer), Some(&environments))?;
        Ok(())
    }

    /// Runs the checkpoint hooks (after a checkpoint is saved); a hook's error names the run folder.
    fn run_checkpoint_hooks(&mut self) -> Result<(), TrainError> {
        let event = CheckpointEvent {
            dir: self.folder.dir(),
            iteration: self.iteration,
            history: &self.history,
            end_reasons: &self.end_reasons,
        };
        for hook in &mut self.checkpoint_hooks {
            hook(&event).map_err(|message| TrainError::Output { path: self.folder.dir().to_owned(), message })?;
        }
        Ok(())
    }
}

/// Where a run stands: zero for a new run, the checkpoint's figures for a resumed one.
#[derive(Debug, Default)]
struct Progress {
    iteration: usize,
    env_steps: u64,
    wall_time_s: f64,
}

/// A new run's learner whose policy starts as another run's (a curriculum's next stage).
fn learner_from(loaded: checkpoint::Checkpoint, ppo_config: PpoConfig, runner: &RunnerConfig) -> Ppo {
    let rng = ChaCha8Rng::seed_from_u64(runner.seed);
    let mut ppo = Ppo::new(loaded.policy, ppo_config, runner.envs, rng, runner.thread_count());
    // A trained policy is sharp (small action noise): a fresh Adam at the initial step size moves it
    // far in the first update (the stage-2 run saw a KL of 75). Continue at the step size the source
    // run ended with, and with its Adam moments when the file is a checkpoint that holds them.
    if ppo.config.schedule == crate::config::Schedule::Adaptive {
        ppo.learning_rate = loaded.info.learning_rate;
    }
    if let Some(optimizer) = loaded.optimizer {
        ppo.optimizer = optimizer;
    }
    if let Some(std) = runner.init_from_noise_std {
        ppo.policy.set_noise_std(std);
    }
    ppo
}

/// The learner of a checkpoint, continued exactly: its policy, optimizer, learning rate and random
/// stream.
fn resumed_learner(loaded: checkpoint::Checkpoint, ppo_config: PpoConfig, runner: &RunnerConfig) -> Ppo {
    let rng = loaded.rng().expect("load() checked the random state");
    let optimizer = loaded.optimizer.expect("checkpoints hold the optimizer");
    let mut ppo = Ppo::new(loaded.policy, ppo_config, runner.envs, rng, runner.thread_count());
    ppo.optimizer = optimizer;
    ppo.learning_rate = loaded.info.learning_rate;
    ppo
}
