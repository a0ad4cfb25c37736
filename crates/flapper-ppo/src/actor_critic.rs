//! The policy: an actor MLP giving each action's mean, a learned state-independent log standard
//! deviation per action, a critic MLP giving the state value, and the observation normalizer both
//! networks read through.

use rand::Rng;

use crate::config::PpoConfig;
use crate::mlp::{Activation, Mlp, Workspace};
use crate::normalizer::Normalizer;

#[derive(Debug, Clone, PartialEq)]
pub struct ActorCritic {
    pub actor: Mlp,
    pub critic: Mlp,
    /// log sigma of each action.
    pub log_std: Vec<f32>,
    pub normalizer: Normalizer,
}

/// ln(2 pi) / 2: the constant of a Gaussian log-density per dimension.
pub const HALF_LN_2PI: f32 = 0.918_938_5;

impl ActorCritic {
    /// Fresh networks (PyTorch's default initialization; the actor's last layer scaled by 0.01 so
    /// the first actions are near zero and the noise explores around them).
    pub fn new(observation_size: usize, action_size: usize, config: &PpoConfig, rng: &mut impl Rng) -> Self {
        let sizes = |hidden: &[usize], out: usize| {
            std::iter::once(observation_size)
                .chain(hidden.iter().copied())
                .chain(std::iter::once(out))
                .collect::<Vec<_>>()
        };
        Self {
            actor: Mlp::new(&sizes(&config.actor_hidden, action_size), config.activation, 0.01, rng),
            critic: Mlp::new(&sizes(&config.critic_hidden, 1), config.activation, 1.0, rng),
            log_std: vec![libm::logf(config.init_noise_std); action_size],
            normalizer: Normalizer::new(observation_size),
        }
    }

    pub fn observation_size(&self) -> usize {
        self.actor.input_size()
    }

    pub fn action_size(&self) -> usize {
        self.actor.output_size()
    }

    pub fn activation(&self) -> Activation {
        self.actor.activation()
    }

    /// The deterministic action (the mean) for raw observations, normalizer frozen: what a trained
    /// policy does at evaluation. The result is a function of the policy and the observations only,
    /// the same bits on every CPU and for any number of rows ([`crate::exact_inference`]).
    pub fn act_deterministic(&self, observations: &[f32], scratch: &mut InferenceScratch, actions: &mut Vec<f32>) {
        let rows = observations.len() / self.observation_size();
        self.normalizer.normalize(observations, &mut scratch.normalized);
        let mean = self.actor.forward_exact(&scratch.normalized, rows, &mut scratch.workspace);
        actions.clear();
        actions.extend_from_slice(mean);
    }

    /// This policy given `extra` more observations after its own, weighted 0 by both networks and read
    /// through the normalizer as they come (mean 0, variance 1): it acts and values as before, and
    /// training can learn to use them.
    pub fn with_inputs_appended(&self, extra: usize) -> Self {
        Self {
            actor: self.actor.with_inputs_appended(extra),
            critic: self.critic.with_inputs_appended(extra),
            log_std: self.log_std.clone(),
            normalizer: self.normalizer.with_features_appended(extra),
        }
    }

    /// Sets every action's noise (standard deviation) to `std`; the log from `libm`, as everywhere in
    /// training, not the platform's (glibc's `logf` differs from it in the last bit for some values).
    pub fn set_noise_std(&mut self, std: f32) {
        self.log_std.fill(libm::logf(std));
    }

    /// Mean standard deviation over actions.
    pub fn mean_std(&self) -> f32 {
        self.log_std.iter().map(|&s| libm::expf(s)).sum::<f32>() / self.log_std.len() as f32
    }
}

/// Buffers for evaluation-time inference.
#[derive(Debug, Clone, Default)]
pub struct InferenceScratch {
    normalized: Vec<f32>,
    workspace: Workspace,
}
