//! The flight task's vectorized environments as the learner sees them: the [`VecEnv`] interface over
//! [`FlightVecEnv`], with the reward kernels as per-step diagnostics.

use flapper_ppo::{EndReason, EnvError, EpisodeRecord, VecEnv};
use flapper_sim::{ModelError, RobotModel};
use flapper_task::termination::EpisodeEnd;
use flapper_task::{FlightVecEnv, ReferenceSource, TaskConfig};

/// Names of the diagnostics: each reward kernel's value in (0, 1], before weighting.
pub const REWARD_TERM_NAMES: [&str; 4] = ["r_position", "r_body_rate", "r_level", "r_energy"];

/// The diagnostics logged after [`REWARD_TERM_NAMES`], in this order, each only when the task weighs it
/// (`reward.action_rate_weight`, `reward.flap_rate_weight`, `reward.glide_hold_weight`,
/// `reward.feathering_weight` above 0), so that the logs of runs without them keep their columns and
/// resume as they were written.
pub const WEIGHED_TERM_NAMES: [&str; 4] = ["r_action_rate", "r_flap_rate", "r_glide_hold", "r_feathering"];

/// Mixed into the run seed for the first episodes' lengths (a stream apart from the environments').
const FIRST_EPISODE_SEED: u64 = 0x5eed_f125_7e9a_0001;

/// The flight task's [`EpisodeEnd`] as the learner counts it (the learner's trait on the task's type).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FlightEnd(pub EpisodeEnd);

impl EndReason for FlightEnd {
    const ALL: &'static [Self] = &{
        let mut all = [FlightEnd(EpisodeEnd::ALL[0]); EpisodeEnd::ALL.len()];
        let mut i = 1;
        while i < all.len() {
            all[i] = FlightEnd(EpisodeEnd::ALL[i]);
            i += 1;
        }
        all
    };

    fn name(self) -> &'static str {
        self.0.name()
    }
}

pub struct FlightEnvs {
    inner: FlightVecEnv,
    diagnostics: Vec<f32>,
    /// Which of [`WEIGHED_TERM_NAMES`] are logged.
    logs_weighed: [bool; 4],
    /// `reward.smoothness_turn_scale_degps` above 0: the learner's smoothness term is weighted per step.
    weighs_smoothness: bool,
}

impl FlightEnvs {
    /// `count` environments on procedural references from `task` on `threads` threads (0 = all cores),
    /// their first episodes cut at spread-out lengths so that launches do not come in bursts.
    pub fn new(
        robot: &RobotModel,
        task: TaskConfig,
        count: usize,
        seed: u64,
        threads: usize,
    ) -> Result<Self, ModelError> {
        let r = &task.reward;
        let logs_weighed =
            [r.action_rate_weight, r.flap_rate_weight, r.glide_hold_weight, r.feathering_weight].map(|w| w > 0.0);
        let weighs_smoothness = task.reward.weighs_smoothness();
        let mut inner = FlightVecEnv::new(robot, task, ReferenceSource::Procedural, count, seed, threads)?;
        inner.spread_first_time_limits(seed ^ FIRST_EPISODE_SEED);
        let mut envs = Self { diagnostics: Vec::new(), inner, logs_weighed, weighs_smoothness };
        envs.diagnostics = vec![0.0; count * envs.logged_terms()];
        Ok(envs)
    }

    /// How many reward kernels each environment logs: the four of [`REWARD_TERM_NAMES`], and those of
    /// [`WEIGHED_TERM_NAMES`] that are weighed.
    fn logged_terms(&self) -> usize {
        REWARD_TERM_NAMES.len() + self.logs_weighed.iter().filter(|&&logged| logged).count()
    }

    pub fn inner(&self) -> &FlightVecEnv {
        &self.inner
    }
}

impl VecEnv for FlightEnvs {
    type EndReason = FlightEnd;

    fn num_envs(&self) -> usize {
        self.inner.len()
    }

    fn observation_size(&self) -> usize {
        self.inner.observation_size()
    }

    fn action_size(&self) -> usize {
        self.inner.action_size()
    }

    /// The clock's two numbers (`[task.observation] clock_hz`): a policy trained without them hears it
    /// with zero weights at first.
    fn appendable_inputs(&self) -> usize {
        self.inner.observation_layout().clock_size()
    }

    fn step(&mut self, actions: &[f32]) -> Result<(), EnvError> {
        self.inner.step(actions)?;
        let per_env = self.logged_terms();
        for (out, t) in self.diagnostics.chunks_exact_mut(per_env).zip(self.inner.reward_terms()) {
            let weighed = self.logs_weighed.into_iter().zip([t.action_rate, t.flap_rate, t.glide_hold, t.feathering]);
            let logged =
                [(true, t.position), (true, t.body_rate), (true, t.level), (true, t.energy)].into_iter().chain(weighed);
            for (o, (_, value)) in out.iter_mut().zip(logged.filter(|(logged, _)| *logged)) {
                *o = value as f32;
            }
        }
        Ok(())
    }

    fn observations(&self) -> &[f32] {
        self.inner.observations()
    }

    fn rewards(&self) -> &[f32] {
        self.inner.rewards()
    }

    fn terminated(&self) -> &[bool] {
        self.inner.terminated()
    }

    fn truncated(&self) -> &[bool] {
        self.inner.truncated()
    }

    fn final_observations(&self) -> &[f32] {
        self.inner.final_observations()
    }

    fn smoothness_weights(&self) -> Option<&[f32]> {
        self.weighs_smoothness.then(|| self.inner.smoothness_weights())
    }

    fn take_finished_episodes(&mut self) -> Vec<EpisodeRecord<FlightEnd>> {
        self.inner
            .take_finished_episodes()
            .into_iter()
            .map(|e| EpisodeRecord { episode_return: e.episode_return, length: e.length, end: FlightEnd(e.end) })
            .collect()
    }

    fn diagnostic_names(&self) -> Vec<String> {
        let extra = self.logs_weighed.into_iter().zip(WEIGHED_TERM_NAMES);
        let extra = extra.filter(|(logged, _)| *logged).map(|(_, name)| name);
        REWARD_TERM_NAMES.iter().copied().chain(extra).map(str::to_string).collect()
    }

    fn diagnostics(&self) -> &[f32] {
        &self.diagnostics
    }

    fn save_state(&self) -> Result<Vec<u8>, EnvError> {
        Ok(serde_json::to_vec(&self.inner.snapshot())?)
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<(), EnvError> {
        let snapshot: flapper_task::vec_env::VecEnvSnapshot = serde_json::from_slice(state)?;
        Ok(self.inner.restore(&snapshot)?)
    }
}
