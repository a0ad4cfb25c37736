//! N environments stepped in parallel on all cores, with automatic reset. Each environment owns its
//! random stream, derived from (seed, index) alone, so a run is bit-identical for a given seed
//! whatever the number of threads.

use std::sync::Arc;

use flapper_sim::{ModelError, RobotModel};
use rayon::prelude::*;

use crate::action::ACTION_SIZE;
use crate::config::TaskConfig;
use crate::env::{EpisodeInfo, FlightEnv, ReferenceSource};
use crate::reward::RewardTerms;
use crate::termination::EpisodeEnd;

/// The batch of environments and the buffers a learner reads after each step.
pub struct FlightVecEnv {
    envs: Vec<FlightEnv>,
    pool: rayon::ThreadPool,
    observation_size: usize,
    observations: Vec<f32>,
    /// Last observation of each episode truncated at the last step (other rows stale).
    final_observations: Vec<f32>,
    rewards: Vec<f32>,
    terminated: Vec<bool>,
    truncated: Vec<bool>,
    terms: Vec<RewardTerms>,
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
        let observation_size = envs.first().map_or(0, |e| e.observation_layout().size());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| ModelError::InvalidValue {
                what: "threads".into(),
                value: format!("{threads} ({e})"),
                why: "could not start the worker threads",
            })?;
        let mut vec_env = Self {
            envs,
            pool,
            observation_size,
            observations: vec![0.0; count * observation_size],
            final_observations: vec![0.0; count * observation_size],
            rewards: vec![0.0; count],
            terminated: vec![false; count],
            truncated: vec![false; count],
            terms: vec![RewardTerms::default(); count],
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
                .zip(self.rewards.par_iter_mut())
                .zip(self.terminated.par_iter_mut().zip(self.truncated.par_iter_mut()))
                .zip(self.terms.par_iter_mut())
                .map(|(((((env, action), (out, final_out)), reward), (terminated, truncated)), terms)| {
                    let result = env.step(action);
                    *reward = result.reward as f32;
                    *terms = result.terms;
                    *terminated = result.end.is_some_and(EpisodeEnd::is_termination);
                    *truncated = result.end.is_some_and(|e| !e.is_termination());
                    let info = result.end.map(|end| env.episode_info(end));
                    if *truncated {
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

    /// For each environment truncated at the last step, its final observation before the reset
    /// (for bootstrapping the value of the cut-off future). Rows of other environments are stale.
    pub fn final_observations(&self) -> &[f32] {
        &self.final_observations
    }

    /// Observations, `len() * observation_size()` numbers, environment by environment.
    pub fn observations(&self) -> &[f32] {
        &self.observations
    }

    pub fn rewards(&self) -> &[f32] {
        &self.rewards
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
