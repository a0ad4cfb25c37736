//! N environments stepped in parallel on all cores, with automatic reset. Each environment owns its
//! random stream, derived from (seed, index) alone, so a run is bit-identical for a given seed
//! whatever the number of threads.

use std::sync::Arc;

use flapper_sim::{ModelError, RobotModel};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::action::ACTION_SIZE;
use crate::config::TaskConfig;
use crate::env::{EnvSnapshot, EpisodeInfo, FlightEnv, ReferenceSource};
use crate::observation::ObservationLayout;
use crate::reward::RewardTerms;
use crate::termination::EpisodeEnd;

/// Every environment mid-episode (see [`EnvSnapshot`]) and the fault count: a training checkpoint's
/// record of the environments, so that a resumed run continues exactly where it stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VecEnvSnapshot {
    envs: Vec<EnvSnapshot>,
    simulation_faults: u64,
}

/// The batch of environments and the buffers a learner reads after each step.
pub struct FlightVecEnv {
    envs: Vec<FlightEnv>,
    pool: rayon::ThreadPool,
    observation_layout: ObservationLayout,
    observation_size: usize,
    observations: Vec<f32>,
    /// Each episode that ended at the last step: its last observation, to bootstrap a truncated
    /// episode from (other rows stale).
    final_observations: Vec<f32>,
    rewards: Vec<f32>,
    position_errors_m: Vec<f32>,
    terminated: Vec<bool>,
    truncated: Vec<bool>,
    terms: Vec<RewardTerms>,
    /// Each environment's weight of the learner's smoothness term at its current observation.
    smoothness_weights: Vec<f32>,
    finished: Vec<EpisodeInfo>,
    simulation_faults: u64,
}

impl FlightVecEnv {
    /// `count` environments on `threads` worker threads (0 = one per core).
    pub fn new(
        robot: &RobotModel,
        config: TaskConfig,
        source: ReferenceSource,
        count: usize,
        seed: u64,
        threads: usize,
    ) -> Result<Self, ModelError> {
        let config = Arc::new(config);
        let envs = (0..count)
            .map(|index| FlightEnv::new(robot, config.clone(), source.clone(), seed, index))
            .collect::<Result<Vec<_>, _>>()?;
        let observation_layout = ObservationLayout::of(&config.observation);
        let observation_size = envs.first().map_or(0, |e| e.observation_layout().size());
        let pool =
            rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| ModelError::InvalidValue {
                what: "threads".into(),
                value: format!("{threads} ({e})"),
                why: "could not start the worker threads",
            })?;
        let mut vec_env = Self {
            envs,
            pool,
            observation_layout,
            observation_size,
            observations: vec![0.0; count * observation_size],
            final_observations: vec![0.0; count * observation_size],
            rewards: vec![0.0; count],
            position_errors_m: vec![0.0; count],
            terminated: vec![false; count],
            truncated: vec![false; count],
            terms: vec![RewardTerms::default(); count],
            smoothness_weights: vec![1.0; count],
            finished: Vec::new(),
            simulation_faults: 0,
        };
        vec_env.observe_all();
        Ok(vec_env)
    }

    fn observe_all(&mut self) {
        let size = self.observation_size;
        let (envs, observations) = (&self.envs, &mut self.observations);
        self.pool.install(|| {
            envs.par_iter().zip(observations.par_chunks_mut(size)).for_each(|(env, out)| env.observe(out));
        });
        self.weigh_smoothness();
    }

    fn weigh_smoothness(&mut self) {
        for (weight, env) in self.smoothness_weights.iter_mut().zip(&self.envs) {
            *weight = env.smoothness_weight();
        }
    }

    pub fn len(&self) -> usize {
        self.envs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.envs.is_empty()
    }

    pub fn observation_size(&self) -> usize {
        self.observation_size
    }

    pub fn action_size(&self) -> usize {
        ACTION_SIZE
    }

    /// The observation's layout (every environment's is the same).
    pub fn observation_layout(&self) -> ObservationLayout {
        self.observation_layout
    }

    /// Steps every environment with its slice of `actions` (`len() * 5` numbers). Finished episodes
    /// are reset at once: their observation is the new episode's first.
    pub fn step(&mut self, actions: &[f32]) -> Result<(), ModelError> {
        assert_eq!(actions.len(), self.envs.len() * ACTION_SIZE, "one action of 5 numbers per environment");
        let size = self.observation_size;
        let results: Vec<Result<Option<EpisodeInfo>, ModelError>> = self.pool.install(|| {
            self.envs
                .par_iter_mut()
                .zip(actions.par_chunks(ACTION_SIZE))
                .zip(self.observations.par_chunks_mut(size).zip(self.final_observations.par_chunks_mut(size)))
                .zip(self.rewards.par_iter_mut().zip(self.position_errors_m.par_iter_mut()))
                .zip(self.terminated.par_iter_mut().zip(self.truncated.par_iter_mut()))
                .zip(self.terms.par_iter_mut())
                .map(|(((((env, action), (out, final_out)), (reward, error)), (terminated, truncated)), terms)| {
                    let result = env.step(action);
                    *reward = result.reward as f32;
                    *error = result.position_error_m as f32;
                    *terms = result.terms;
                    *terminated = result.end.is_some_and(EpisodeEnd::is_termination);
                    *truncated = result.end.is_some_and(|e| !e.is_termination());
                    let info = result.end.map(|end| env.episode_info(end));
                    if result.end == Some(EpisodeEnd::SimulationFault) {
                        // The state after a fault is broken: bootstrap from the last sound
                        // observation, the one this step's action was chosen on (still in `out`).
                        final_out.copy_from_slice(out);
                    } else if result.end.is_some() {
                        env.observe(final_out);
                    }
                    if info.is_some() {
                        env.reset()?;
                    }
                    env.observe(out);
                    Ok(info)
                })
                .collect()
        });
        for result in results {
            if let Some(info) = result? {
                if info.end == EpisodeEnd::SimulationFault {
                    self.simulation_faults += 1;
                }
                self.finished.push(info);
            }
        }
        self.weigh_smoothness();
        Ok(())
    }

    /// Starts a new episode in every environment, each continuing its own random stream.
    pub fn reset_all(&mut self) -> Result<(), ModelError> {
        self.pool.install(|| self.envs.par_iter_mut().try_for_each(|env| env.reset()))?;
        self.finished.clear();
        self.observe_all();
        Ok(())
    }

    /// Starts a new episode in every environment with its random stream drawn afresh from (`seed`,
    /// its index), as if the batch had just been built with `seed`.
    pub fn restart(&mut self, seed: u64) -> Result<(), ModelError> {
        self.pool.install(|| self.envs.par_iter_mut().try_for_each(|env| env.restart(seed)))?;
        self.finished.clear();
        self.observe_all();
        Ok(())
    }

    /// Shortens each environment's current (first) episode to a time limit drawn uniformly from
    /// 1..=`episode.max_steps` with `seed`, as rsl_rl's random initial episode length does: without
    /// it, every episode of a batch launches and reaches the time limit at the same step, and the
    /// learner sees bursts of launches and of truncations.
    pub fn spread_first_time_limits(&mut self, seed: u64) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        for env in &mut self.envs {
            let max_steps = env.config().episode.max_steps;
            env.shorten_episode(rng.random_range(1..=max_steps));
        }
    }

    /// Every environment as it stands (between steps), to continue later with [`FlightVecEnv::restore`].
    pub fn snapshot(&self) -> VecEnvSnapshot {
        let envs = self.pool.install(|| self.envs.par_iter().map(FlightEnv::snapshot).collect());
        VecEnvSnapshot { envs, simulation_faults: self.simulation_faults }
    }

    /// Continues from `snapshot`, taken from a batch of as many environments with the same model, task
    /// and seed. Episodes finished since the last [`FlightVecEnv::take_finished_episodes`] are dropped.
    pub fn restore(&mut self, snapshot: &VecEnvSnapshot) -> Result<(), ModelError> {
        if snapshot.envs.len() != self.envs.len() {
            return Err(ModelError::InvalidValue {
                what: "environment snapshot".into(),
                value: format!("{} environments", snapshot.envs.len()),
                why: "the batch has another number of environments",
            });
        }
        self.pool.install(|| self.envs.par_iter_mut().zip(&snapshot.envs).try_for_each(|(env, s)| env.restore(s)))?;
        self.simulation_faults = snapshot.simulation_faults;
        self.finished.clear();
        self.observe_all();
        Ok(())
    }

    /// For each environment whose episode ended at the last step, its final observation before the
    /// reset (a truncated episode bootstraps the value of its cut-off future from it), or after a
    /// simulation fault the last observation before the fault (the broken state is never observed).
    /// Rows of other environments are stale.
    pub fn final_observations(&self) -> &[f32] {
        &self.final_observations
    }

    /// Observations, `len() * observation_size()` numbers, environment by environment.
    pub fn observations(&self) -> &[f32] {
        &self.observations
    }

    /// Each environment's distance from its target after the last step (m), before any reset.
    pub fn position_errors_m(&self) -> &[f32] {
        &self.position_errors_m
    }

    /// Environment `index` flies `source` from now on, starting a new episode on it.
    pub fn set_reference_source(&mut self, index: usize, source: ReferenceSource) -> Result<(), ModelError> {
        let size = self.observation_size;
        let env = self.envs.get_mut(index).ok_or_else(|| ModelError::InvalidValue {
            what: "environment index".into(),
            value: index.to_string(),
            why: "no such environment",
        })?;
        env.set_reference_source(source)?;
        env.observe(&mut self.observations[index * size..(index + 1) * size]);
        Ok(())
    }

    pub fn rewards(&self) -> &[f32] {
        &self.rewards
    }

    /// Each environment's weight of the learner's smoothness term for the action chosen at its
    /// current observation ([`FlightEnv::smoothness_weight`]).
    pub fn smoothness_weights(&self) -> &[f32] {
        &self.smoothness_weights
    }

    pub fn terminated(&self) -> &[bool] {
        &self.terminated
    }

    pub fn truncated(&self) -> &[bool] {
        &self.truncated
    }

    /// Each environment's reward terms at the last step.
    pub fn reward_terms(&self) -> &[RewardTerms] {
        &self.terms
    }

    /// Episodes finished since the last call, in environment order within each step.
    pub fn take_finished_episodes(&mut self) -> Vec<EpisodeInfo> {
        std::mem::take(&mut self.finished)
    }

    /// Episodes ended by a simulation fault so far.
    pub fn simulation_faults(&self) -> u64 {
        self.simulation_faults
    }

    pub fn envs(&self) -> &[FlightEnv] {
        &self.envs
    }

    pub fn envs_mut(&mut self) -> &mut [FlightEnv] {
        &mut self.envs
    }
}
