//! The learner's settings, each named as in the literature and defaulting to rsl_rl's PPO values
//! (Rudin et al. 2022), which the paper's training used. A TOML `[ppo]` / `[runner]` table overrides any.

use serde::{Deserialize, Serialize};

use crate::mlp::Activation;

/// A setting no run could use, named with its value.
#[derive(Debug, thiserror::Error)]
#[error("config value {key} = {value}: {why}")]
pub struct InvalidSetting {
    pub key: &'static str,
    pub value: String,
    pub why: &'static str,
}

/// The distance the temporal smoothness term ([`PpoConfig::smoothness_coef`]) prices between the actor's
/// mean and each neighbour's.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SmoothnessNorm {
    /// |gap|^2: its pull shrinks with the gap, so a small oscillation costs almost nothing.
    #[default]
    Squared,
    /// |gap| (CAPS's own Euclidean distance, Mysore et al. 2021), smoothed below
    /// [`crate::loss::EUCLIDEAN_SMOOTHING`]: a pull of the same strength whatever the gap, so holding still
    /// is where the term is least, as an L1 penalty makes weights exactly zero.
    Euclidean,
}

impl SmoothnessNorm {
    pub fn is_squared(&self) -> bool {
        *self == SmoothnessNorm::Squared
    }
}

/// How the learning rate moves between updates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Schedule {
    /// Fixed at `learning_rate`.
    Fixed,
    /// Divided by 1.5 when the KL of a minibatch exceeds 2 `desired_kl`, multiplied by 1.5 when
    /// below half of it, within [`crate::ppo::LEARNING_RATE_RANGE`] ([`crate::ppo::adapted_learning_rate`]).
    Adaptive,
}

/// PPO (Schulman et al. 2017) and the actor-critic networks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PpoConfig {
    /// Steps each environment collects per iteration (rollout length).
    pub steps_per_env: usize,
    /// Passes over each rollout.
    pub epochs: usize,
    /// Minibatches per pass.
    pub minibatches: usize,
    /// epsilon of the clipped surrogate (and of the clipped value loss).
    pub clip: f32,
    pub clipped_value_loss: bool,
    pub value_loss_coef: f32,
    pub entropy_coef: f32,
    /// gamma, the discount per step.
    pub gamma: f32,
    /// lambda of generalized advantage estimation.
    pub lambda: f32,
    /// Global L2 norm the gradient is clipped to.
    pub max_grad_norm: f32,
    /// Adam's initial step size.
    pub learning_rate: f32,
    pub schedule: Schedule,
    /// Target KL of the adaptive schedule.
    pub desired_kl: f32,
    /// Normalize advantages over each rollout to zero mean and unit variance.
    pub normalize_advantages: bool,
    pub actor_hidden: Vec<usize>,
    pub critic_hidden: Vec<usize>,
    pub activation: Activation,
    /// Initial standard deviation of every action (the log-std is learned, state-independent).
    pub init_noise_std: f32,
    /// Weight of the temporal smoothness of the actor's mean (CAPS, Mysore et al. 2021; not rsl_rl's,
    /// 0 = off): the loss adds this times the mean over samples of d(mu(s_t), mu_old(s_t-1)) +
    /// d(mu(s_t), mu_old(s_t+1)) over the neighbours in the same episode and rollout, mu_old being
    /// the means at collection and d the distance `smoothness_norm` names (by default the squared one).
    /// It acts on the mean, so the exploration noise does not drown it.
    pub smoothness_coef: f32,
    /// The distance `smoothness_coef` prices: squared (the default) or CAPS's Euclidean one.
    /// Left out of a written config when squared, so that configs written before it read the same.
    #[serde(skip_serializing_if = "SmoothnessNorm::is_squared")]
    pub smoothness_norm: SmoothnessNorm,
    /// Each action's share of the smoothness distance, in action order: its gap to the neighbours'
    /// means is multiplied by this before `smoothness_norm` measures it (0 leaves that action unpriced).
    /// Empty (the default, left out of a written config) prices every action alike; otherwise one
    /// number per action, each in [0, 1000].
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub smoothness_action_scale: Vec<f32>,
    /// Weight of the temporal curvature of the actor's mean (0 = off): the loss adds this times the
    /// mean over samples of |mu(s_t) - (mu_old(s_t-1) + mu_old(s_t+1)) / 2|^2, over the samples with
    /// both neighbours in the same episode and rollout, every action alike and every sample alike (the
    /// environment's smoothness weights and `smoothness_action_scale` price `smoothness_coef`'s term
    /// only). A stroke of amplitude A at frequency f costs about A^2 f^4 here where its lift and thrust
    /// grow about as (A f)^2, and the first difference `smoothness_coef` prices as (A f)^2 too: this is
    /// the term that prefers the slower, wider stroke. Left out of a written config when 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub curvature_coef: f32,
}

fn is_zero(value: &f32) -> bool {
    *value == 0.0
}

impl Default for PpoConfig {
    fn default() -> Self {
        Self {
            steps_per_env: 24,
            epochs: 5,
            minibatches: 4,
            clip: 0.2,
            clipped_value_loss: true,
            value_loss_coef: 1.0,
            entropy_coef: 0.01,
            gamma: 0.99,
            lambda: 0.95,
            max_grad_norm: 1.0,
            learning_rate: 1e-3,
            schedule: Schedule::Adaptive,
            desired_kl: 0.01,
            normalize_advantages: true,
            actor_hidden: vec![256, 128, 64],
            critic_hidden: vec![256, 128, 64],
            activation: Activation::Elu,
            init_noise_std: 1.0,
            smoothness_coef: 0.0,
            smoothness_norm: SmoothnessNorm::Squared,
            smoothness_action_scale: Vec::new(),
            curvature_coef: 0.0,
        }
    }
}

/// How long a run is, how many environments it drives, and how often it saves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RunnerConfig {
    /// Parallel environments (the paper: 256).
    pub envs: usize,
    /// PPO iterations; each collects `envs * steps_per_env` environment steps.
    pub iterations: usize,
    pub seed: u64,
    /// Worker threads for environments and network maths (0 = one per core).
    pub threads: usize,
    /// Save a checkpoint every this many iterations (and at the end). A checkpoint holds the
    /// environments mid-episode, so that resuming continues the uninterrupted run exactly.
    pub checkpoint_every: usize,
    /// With `--init-from`: start from this action noise (standard deviation of every action) instead of
    /// the source policy's. A later stage may restart a policy whose noise grew through training.
    pub init_from_noise_std: Option<f32>,
}

impl Default for RunnerConfig {
    fn default() -> Self {
        Self { envs: 256, iterations: 1500, seed: 1, threads: 0, checkpoint_every: 100, init_from_noise_std: None }
    }
}

impl PpoConfig {
    /// Every setting against its range, one table for the counts and one for the real numbers (NaN
    /// and infinity fail every range).
    pub fn validate(&self) -> Result<(), InvalidSetting> {
        for (key, value, max, why) in [
            ("ppo.steps_per_env", self.steps_per_env, 10_000, "must be 1 to 10000"),
            ("ppo.epochs", self.epochs, 1000, "must be 1 to 1000"),
            ("ppo.minibatches", self.minibatches, 100_000, "must be 1 to 100000"),
        ] {
            if value == 0 || value > max {
                return Err(InvalidSetting { key, value: value.to_string(), why });
            }
        }
        let positive = |value: f32, max: f32| value > 0.0 && value <= max;
        let not_negative = |value: f32, max: f32| value >= 0.0 && value <= max;
        for (key, value, fits, why) in [
            ("ppo.clip", self.clip, positive(self.clip, 10.0), "must be in (0, 10]"),
            ("ppo.max_grad_norm", self.max_grad_norm, positive(self.max_grad_norm, 1e6), "must be in (0, 1e6]"),
            ("ppo.learning_rate", self.learning_rate, positive(self.learning_rate, 1.0), "must be in (0, 1]"),
            ("ppo.desired_kl", self.desired_kl, positive(self.desired_kl, 10.0), "must be in (0, 10]"),
            ("ppo.init_noise_std", self.init_noise_std, positive(self.init_noise_std, 100.0), "must be in (0, 100]"),
            (
                "ppo.value_loss_coef",
                self.value_loss_coef,
                not_negative(self.value_loss_coef, 1e3),
                "must be in [0, 1000]",
            ),
            ("ppo.entropy_coef", self.entropy_coef, not_negative(self.entropy_coef, 1e3), "must be in [0, 1000]"),
            (
                "ppo.smoothness_coef",
                self.smoothness_coef,
                not_negative(self.smoothness_coef, 1e3),
                "must be in [0, 1000]",
            ),
            ("ppo.curvature_coef", self.curvature_coef, not_negative(self.curvature_coef, 1e3), "must be in [0, 1000]"),
            ("ppo.gamma", self.gamma, not_negative(self.gamma, 1.0), "must be in [0, 1]"),
            ("ppo.lambda", self.lambda, not_negative(self.lambda, 1.0), "must be in [0, 1]"),
        ] {
            if !fits {
                return Err(InvalidSetting { key, value: value.to_string(), why });
            }
        }
        if let Some(bad) = self.smoothness_action_scale.iter().find(|&&s| !not_negative(s, 1e3)) {
            return Err(InvalidSetting {
                key: "ppo.smoothness_action_scale",
                value: bad.to_string(),
                why: "each action's share must be in [0, 1000]",
            });
        }
        for (key, sizes) in [("ppo.actor_hidden", &self.actor_hidden), ("ppo.critic_hidden", &self.critic_hidden)] {
            if sizes.is_empty() || sizes.iter().any(|&s| s == 0 || s > 4096) {
                return Err(InvalidSetting {
                    key,
                    value: format!("{sizes:?}"),
                    why: "needs at least one hidden layer, each of 1 to 4096 units",
                });
            }
        }
        Ok(())
    }

    /// Checks the settings that depend on the environment's actions (`action_names`, in action order).
    pub fn validate_for_actions(&self, action_names: &[&str]) -> Result<(), InvalidSetting> {
        let scales = &self.smoothness_action_scale;
        if !scales.is_empty() && scales.len() != action_names.len() {
            return Err(InvalidSetting {
                key: "ppo.smoothness_action_scale",
                value: format!(
                    "{scales:?} ({} shares for the {} actions {})",
                    scales.len(),
                    action_names.len(),
                    action_names.join(", ")
                ),
                why: "needs one share per action, in that order, or none",
            });
        }
        Ok(())
    }

    /// Whether the loss needs each sample's neighbours in time (a smoothness or a curvature term).
    pub fn needs_neighbours(&self) -> bool {
        self.smoothness_coef > 0.0 || self.curvature_coef > 0.0
    }

    /// The share of action `j` in the smoothness distance (1 where `smoothness_action_scale` is empty).
    pub fn smoothness_scale(&self, j: usize) -> f32 {
        self.smoothness_action_scale.get(j).copied().unwrap_or(1.0)
    }
}

impl RunnerConfig {
    pub fn validate(&self, ppo: &PpoConfig) -> Result<(), InvalidSetting> {
        let invalid = |key, value: String, why| Err(InvalidSetting { key, value, why });
        if self.envs == 0 || self.envs > 65_536 {
            return invalid("runner.envs", self.envs.to_string(), "must be 1 to 65536");
        }
        if self.iterations == 0 || self.iterations > 10_000_000 {
            return invalid("runner.iterations", self.iterations.to_string(), "must be 1 to 10000000");
        }
        if self.envs * ppo.steps_per_env > 4_000_000 {
            return invalid(
                "ppo.steps_per_env",
                ppo.steps_per_env.to_string(),
                "envs x steps_per_env must be at most 4000000 samples per rollout",
            );
        }
        if self.checkpoint_every == 0 {
            return invalid("runner.checkpoint_every", "0".into(), "must be at least 1");
        }
        if self.threads > 1024 {
            return invalid("runner.threads", self.threads.to_string(), "must be at most 1024 (0 = one per core)");
        }
        if let Some(std) = self.init_from_noise_std
            && !(std.is_finite() && std > 0.0 && std <= 10.0)
        {
            return invalid("runner.init_from_noise_std", std.to_string(), "must be in (0, 10]");
        }
        if self.envs * ppo.steps_per_env < ppo.minibatches {
            return invalid(
                "ppo.minibatches",
                ppo.minibatches.to_string(),
                "more minibatches than samples per rollout",
            );
        }
        Ok(())
    }

    /// The number of threads to use: `threads`, or one per core when 0.
    pub fn thread_count(&self) -> usize {
        threads_or_all_cores(self.threads)
    }
}

/// `requested` threads, or one per core when 0 (the meaning of 0 in every `threads` setting).
pub fn threads_or_all_cores(requested: usize) -> usize {
    if requested > 0 { requested } else { std::thread::available_parallelism().map_or(1, |n| n.get()) }
}
