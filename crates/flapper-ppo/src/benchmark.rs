//! Throughput of the network update on the PPO workload, through the path training takes:
//! [`Ppo::update`] over a full rollout of synthetic samples (minibatch gathering, the loss and its
//! gradients with the actor's and the critic's halves side by side, gradient clipping, Adam and the
//! adaptive learning rate). Also the latency of one policy call, the on-board controller's cost. Used by
//! `flapper bench`.

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::actor_critic::{ActorCritic, InferenceScratch};
use crate::config::PpoConfig;
use crate::mlp::Workspace;
use crate::ppo::Ppo;

#[derive(Debug, Clone)]
pub struct NetworkThroughput {
    pub minibatch: usize,
    pub threads: usize,
    /// Median over repeats of samples per second through one gradient step of actor and critic
    /// (forward, backward, Adam): epochs x rollout samples / the update's wall time.
    pub median_samples_per_s: f64,
    pub repeats: usize,
}

/// Times `repeats` updates of a learner with `config`'s networks and schedule over rollouts of `envs`
/// environments (filled with random observations and rewards; the filling is not timed).
pub fn time_ppo_update(
    observation_size: usize,
    action_size: usize,
    envs: usize,
    config: &PpoConfig,
    threads: usize,
    repeats: usize,
) -> NetworkThroughput {
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let policy = ActorCritic::new(observation_size, action_size, config, &mut rng);
    let mut ppo = Ppo::new(policy, config.clone(), envs, ChaCha8Rng::seed_from_u64(1), threads);
    let mut observations = vec![0.0f32; envs * observation_size];
    let mut actions = vec![0.0f32; envs * action_size];
    let (no_end, mut rewards) = (vec![false; envs], vec![0.0f32; envs]);
    let samples = config.epochs * config.steps_per_env * envs;
    let mut rates = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) + 1 {
        for _ in 0..config.steps_per_env {
            observations.iter_mut().for_each(|x| *x = rng.random_range(-1.0..1.0));
            rewards.iter_mut().for_each(|r| *r = rng.random_range(0.0..1.0));
            ppo.act(&observations, &mut actions);
            ppo.process_step(&rewards, &no_end, &no_end, &observations);
        }
        ppo.finish_rollout(&observations);
        let began = Instant::now();
        ppo.update();
        rates.push(samples as f64 / began.elapsed().as_secs_f64());
    }
    rates.remove(0); // warm-up: buffers allocated on the first pass
    rates.sort_by(f64::total_cmp);
    NetworkThroughput {
        minibatch: config.steps_per_env * envs / config.minibatches,
        threads,
        median_samples_per_s: rates[rates.len() / 2],
        repeats: rates.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_update_benchmark_counts_every_gradient_sample() {
        let config = PpoConfig { actor_hidden: vec![8], critic_hidden: vec![8], ..PpoConfig::default() };
        let t = time_ppo_update(6, 2, 16, &config, 1, 3);
        assert_eq!((t.minibatch, t.threads, t.repeats), (16 * 24 / 4, 1, 3));
        assert!(t.median_samples_per_s.is_finite() && t.median_samples_per_s > 0.0, "{t:?}");
    }
}

/// Median time of one policy call on one thread: one observation to its actions.
#[derive(Debug, Clone)]
pub struct PolicyLatency {
    /// Through `ActorCritic::act_deterministic` (normalizer and the CPU-independent forward pass): what
    /// evaluation, the Python binding and an on-board controller run.
    pub exact_us: f64,
    /// The actor alone through the CPU-independent forward pass.
    pub exact_actor_us: f64,
    /// The actor alone through the training path (`fixed_matmul`, on the CPU's widest vector path), for comparison.
    pub training_path_us: f64,
    pub calls: usize,
}

/// Times `calls` single-observation calls of a policy with `config`'s networks (random weights and
/// observations; the time does not depend on the values).
pub fn time_policy_latency(
    observation_size: usize,
    action_size: usize,
    config: &PpoConfig,
    calls: usize,
) -> PolicyLatency {
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let policy = ActorCritic::new(observation_size, action_size, config, &mut rng);
    let observation: Vec<f32> = (0..observation_size).map(|_| rng.random_range(-1.0..1.0)).collect();
    let calls = calls.max(1);
    let median_us = |mut call: Box<dyn FnMut() + '_>| {
        call(); // warm-up: buffers allocated on the first call
        let mut times: Vec<f64> = (0..calls)
            .map(|_| {
                let began = Instant::now();
                call();
                began.elapsed().as_secs_f64() * 1e6
            })
            .collect();
        times.sort_by(f64::total_cmp);
        times[times.len() / 2]
    };
    let (mut scratch, mut actions) = (InferenceScratch::default(), Vec::new());
    let exact_us = median_us(Box::new(|| policy.act_deterministic(&observation, &mut scratch, &mut actions)));
    let mut workspace = Workspace::default();
    let exact_actor_us = median_us(Box::new(|| {
        std::hint::black_box(policy.actor.forward_exact(&observation, 1, &mut workspace));
    }));
    let training_path_us = median_us(Box::new(|| {
        std::hint::black_box(policy.actor.forward(&observation, 1, &mut workspace, 1));
    }));
    PolicyLatency { exact_us, exact_actor_us, training_path_us, calls }
}
