//! The interface between any batch of environments and the learner (rsl_rl's `VecEnv`): N
//! environments stepped together with automatic reset, flat observation and action buffers. The flight
//! task and the inverted-pendulum check both implement it; the learner sees nothing else of them.

/// An environment's error, passed through the learner unchanged.
pub type EnvError = Box<dyn std::error::Error + Send + Sync>;

/// Why an episode ended, as an environment defines it (the flight task's `EpisodeEnd`, the
/// pendulum's fall or time limit). The training log counts each in its own `end_<name>` column.
pub trait EndReason: Copy + Eq + std::fmt::Debug + 'static {
    /// Every value, in the order of the training log's columns.
    const ALL: &'static [Self];
    /// Its name in the training log.
    fn name(self) -> &'static str;
}

/// One finished episode.
#[derive(Debug, Clone, PartialEq)]
pub struct EpisodeRecord<R> {
    pub episode_return: f64,
    pub length: usize,
    pub end: R,
}

pub trait VecEnv {
    /// Why this environment's episodes end.
    type EndReason: EndReason;

    fn num_envs(&self) -> usize;
    fn observation_size(&self) -> usize;
    fn action_size(&self) -> usize;

    /// How many of the observation's last numbers a policy trained without them may be given, weighted
    /// 0, when a run starts from its file (`Start::InitFrom`): inputs that only add to what it saw.
    fn appendable_inputs(&self) -> usize {
        0
    }

    /// Applies one action per environment (`num_envs() * action_size()` numbers, environment by
    /// environment). Episodes that end are reset at once: the next observation is the new episode's.
    fn step(&mut self, actions: &[f32]) -> Result<(), EnvError>;

    /// Current observations, `num_envs() * observation_size()` numbers.
    fn observations(&self) -> &[f32];
    /// Rewards of the last step.
    fn rewards(&self) -> &[f32];
    /// The episode ended at the last step by a failure: its value after the end is zero.
    fn terminated(&self) -> &[bool];
    /// The episode was cut at the last step (time limit): the learner bootstraps its value from
    /// [`VecEnv::final_observations`].
    fn truncated(&self) -> &[bool];
    /// For each truncated environment, its last observation before the reset (other rows unspecified).
    fn final_observations(&self) -> &[f32];

    /// The weight of the learner's smoothness term (`ppo.smoothness_coef`) for the action about to be
    /// chosen at each environment's current observation, or `None` for 1 everywhere (the default).
    fn smoothness_weights(&self) -> Option<&[f32]> {
        None
    }

    /// Episodes finished since the last call.
    fn take_finished_episodes(&mut self) -> Vec<EpisodeRecord<Self::EndReason>>;

    /// Names of per-step diagnostics the learner averages and logs (e.g. reward terms).
    fn diagnostic_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Their values at the last step, `num_envs() * diagnostic_names().len()` numbers.
    fn diagnostics(&self) -> &[f32] {
        &[]
    }

    /// Everything the environments will do next depends on, as bytes (mid-episode states, random
    /// streams). Checkpoints hold it, so that a resumed run continues the uninterrupted one exactly
    /// without restarting any episode.
    fn save_state(&self) -> Result<Vec<u8>, EnvError>;
    /// Continues from bytes written by [`VecEnv::save_state`] of a batch built the same way.
    fn restore_state(&mut self, state: &[u8]) -> Result<(), EnvError>;
}
