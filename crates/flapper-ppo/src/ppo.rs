//! PPO (Schulman et al. 2017) as rsl_rl runs it: act and record, bootstrap truncated episodes,
//! generalized advantages, then `epochs` passes of `minibatches` clipped-surrogate updates with a
//! clipped value loss, an entropy bonus, global gradient clipping, Adam, and the adaptive
//! learning-rate schedule on the policy's KL divergence. The loss and its gradients are in `loss`.

use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::actor_critic::{ActorCritic, HALF_LN_2PI};
use crate::adam::Adam;
use crate::config::{PpoConfig, Schedule};
use crate::loss::{Gradients, LossScratch, Minibatch, loss_and_gradients};
use crate::mlp::Workspace;
use crate::normal::standard_normal;
use crate::storage::{RolloutStorage, Transition};

/// Adam state for every parameter of the policy (one optimizer over all, as in rsl_rl, kept as
/// three because the parameters live in three vectors).
#[derive(Debug, Clone, PartialEq)]
pub struct Optimizer {
    pub actor: Adam,
    pub critic: Adam,
    pub log_std: Adam,
}

/// Averages over an update's minibatches.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct UpdateStats {
    pub surrogate_loss: f64,
    pub value_loss: f64,
    pub entropy: f64,
    pub kl: f64,
    pub clip_fraction: f64,
    /// Gradient norm before clipping.
    pub grad_norm: f64,
    /// Learning rate after the update.
    pub learning_rate: f64,
    pub action_std: f64,
    /// The smoothness term's mean (`smoothness_coef` above 0; None when off).
    pub smoothness: Option<f64>,
    /// The curvature term's mean (`curvature_coef` above 0; None when off).
    pub curvature: Option<f64>,
}

/// How many samples' observations one task of the minibatch gather copies.
const GATHER_ROWS: usize = 64;

/// The adaptive schedule's bounds on the learning rate (rsl_rl's).
pub const LEARNING_RATE_RANGE: (f32, f32) = (1e-5, 1e-2);

/// The adaptive schedule's step (rsl_rl's): the learning rate after a minibatch whose policy moved by
/// `kl` against the target `desired_kl`: divided by 1.5 above twice the target, multiplied by 1.5
/// below half of it (a KL of exactly zero says nothing and changes nothing), kept within
/// [`LEARNING_RATE_RANGE`].
pub fn adapted_learning_rate(learning_rate: f32, kl: f64, desired_kl: f32) -> f32 {
    let target = desired_kl as f64;
    let (lowest, highest) = LEARNING_RATE_RANGE;
    if kl > 2.0 * target {
        (learning_rate / 1.5).max(lowest)
    } else if kl < 0.5 * target && kl > 0.0 {
        (learning_rate * 1.5).min(highest)
    } else {
        learning_rate
    }
}

/// The learner: policy, optimizer, learning rate, random stream and rollout storage.
pub struct Ppo {
    pub config: PpoConfig,
    pub policy: ActorCritic,
    pub optimizer: Optimizer,
    pub learning_rate: f32,
    /// Draws the exploration noise and the minibatch shuffles.
    pub rng: ChaCha8Rng,
    pub storage: RolloutStorage,
    /// log sigma when the current rollout was collected.
    rollout_log_std: Vec<f32>,
    threads: usize,
    normalized: Vec<f32>,
    actor_ws: Workspace,
    critic_ws: Workspace,
    bootstrap_rows: Vec<f32>,
    minibatch: Minibatch,
    transition: Transition,
    loss_scratch: LossScratch,
    grads: Gradients,
}

impl Ppo {
    pub fn new(policy: ActorCritic, config: PpoConfig, envs: usize, rng: ChaCha8Rng, threads: usize) -> Self {
        let optimizer = Optimizer {
            actor: Adam::new(policy.actor.params().len(), config.learning_rate),
            critic: Adam::new(policy.critic.params().len(), config.learning_rate),
            log_std: Adam::new(policy.log_std.len(), config.learning_rate),
        };
        let storage = RolloutStorage::new(config.steps_per_env, envs, policy.observation_size(), policy.action_size());
        let grads = Gradients::zeros(&policy);
        Self {
            learning_rate: config.learning_rate,
            rollout_log_std: policy.log_std.clone(),
            config,
            policy,
            optimizer,
            rng,
            storage,
            threads: threads.max(1),
            normalized: Vec::new(),
            actor_ws: Workspace::default(),
            critic_ws: Workspace::default(),
            bootstrap_rows: Vec::new(),
            minibatch: Minibatch::default(),
            transition: Transition::default(),
            loss_scratch: LossScratch::default(),
            grads,
        }
    }

    /// Records the observations of the current step (updating the normalizer), samples an action per
    /// environment into `actions` and records it with its log-probability and the state value.
    pub fn act(&mut self, observations: &[f32], actions: &mut [f32]) {
        let (envs, a_size, o_size) = (self.storage.envs, self.policy.action_size(), self.policy.observation_size());
        assert_eq!(observations.len(), envs * o_size);
        assert_eq!(actions.len(), envs * a_size);
        if self.storage.step() == 0 {
            self.rollout_log_std.clone_from(&self.policy.log_std);
        }
        self.policy.normalizer.update(observations);
        self.policy.normalizer.normalize(observations, &mut self.normalized);
        let (policy, normalized, threads) = (&self.policy, &self.normalized, self.threads);
        let (actor_ws, critic_ws) = (&mut self.actor_ws, &mut self.critic_ws);
        // Actor and critic side by side, each on half the threads (their products split by rows).
        let (means, values) = if threads >= 2 {
            let half = threads / 2;
            rayon::join(
                || policy.actor.forward(normalized, envs, actor_ws, half),
                || policy.critic.forward(normalized, envs, critic_ws, half),
            )
        } else {
            (
                policy.actor.forward(normalized, envs, actor_ws, threads),
                policy.critic.forward(normalized, envs, critic_ws, threads),
            )
        };
        let t = &mut self.transition;
        t.observations.clone_from(&self.normalized);
        t.means.clear();
        t.means.extend_from_slice(means);
        t.values.clear();
        t.values.extend_from_slice(values);
        t.log_probs.clear();
        let std: Vec<f32> = self.policy.log_std.iter().map(|&l| libm::expf(l)).collect();
        let constant = -self.policy.log_std.iter().sum::<f32>() - a_size as f32 * HALF_LN_2PI;
        for env in 0..envs {
            let mut log_prob = constant;
            for (j, sigma) in std.iter().enumerate() {
                let noise = standard_normal(&mut self.rng);
                let k = env * a_size + j;
                actions[k] = means[k] + sigma * noise;
                log_prob -= 0.5 * noise * noise;
            }
            t.log_probs.push(log_prob);
        }
        t.actions.clear();
        t.actions.extend_from_slice(actions);
        t.smoothness_weights.clear();
    }

    /// Records the weight of the smoothness term for the actions `act` just chose (one per
    /// environment; [`crate::VecEnv::smoothness_weights`]). Without a call every weight is 1.
    pub fn weigh_smoothness(&mut self, weights: &[f32]) {
        assert_eq!(weights.len(), self.storage.envs, "one smoothness weight per environment");
        self.transition.smoothness_weights.clear();
        self.transition.smoothness_weights.extend_from_slice(weights);
    }

    /// Records the environments' answer to the last `act` and stores the step's transition. A
    /// truncated episode's reward gains gamma times the value of its final observation (its future
    /// was cut, not zero).
    pub fn process_step(
        &mut self,
        rewards: &[f32],
        terminated: &[bool],
        truncated: &[bool],
        final_observations: &[f32],
    ) {
        let o_size = self.policy.observation_size();
        let t = &mut self.transition;
        t.rewards.clear();
        t.rewards.extend_from_slice(rewards);
        t.dones.clear();
        t.dones.extend((0..rewards.len()).map(|k| terminated[k] || truncated[k]));
        let cut: Vec<usize> = (0..rewards.len()).filter(|&k| truncated[k] && !terminated[k]).collect();
        if !cut.is_empty() {
            self.bootstrap_rows.clear();
            for &k in &cut {
                self.bootstrap_rows.extend_from_slice(&final_observations[k * o_size..(k + 1) * o_size]);
            }
            self.policy.normalizer.normalize(&self.bootstrap_rows, &mut self.normalized);
            let values = self.policy.critic.forward(&self.normalized, cut.len(), &mut self.critic_ws, self.threads);
            for (&k, v) in cut.iter().zip(values) {
                self.transition.rewards[k] += self.config.gamma * v;
            }
        }
        self.storage.add_transition(&self.transition);
    }

    /// Closes the rollout: values of the observations after its last step, GAE, advantage normalization.
    pub fn finish_rollout(&mut self, observations: &[f32]) {
        let envs = self.storage.envs;
        self.policy.normalizer.normalize(observations, &mut self.normalized);
        let last = self.policy.critic.forward(&self.normalized, envs, &mut self.critic_ws, self.threads).to_vec();
        self.storage.compute_returns(&last, self.config.gamma, self.config.lambda);
        if self.config.normalize_advantages {
            self.storage.normalize_advantages();
        }
    }

    /// `epochs` passes of `minibatches` gradient steps over the finished rollout; clears it.
    pub fn update(&mut self) -> UpdateStats {
        let total = self.storage.len();
        let size = total / self.config.minibatches;
        let mut order: Vec<usize> = (0..total).collect();
        let mut stats = UpdateStats::default();
        let (mut count, mut smoothness, mut curvature) = (0.0, 0.0, 0.0);
        for _ in 0..self.config.epochs {
            order.shuffle(&mut self.rng);
            for chunk in order.chunks_exact(size) {
                self.gather(chunk);
                let terms = loss_and_gradients(
                    &self.policy,
                    &self.config,
                    &self.minibatch,
                    &mut self.loss_scratch,
                    &mut self.grads,
                    self.threads,
                );
                if self.config.schedule == Schedule::Adaptive {
                    self.learning_rate = adapted_learning_rate(self.learning_rate, terms.kl, self.config.desired_kl);
                }
                let norm = self.grads.clip_global_norm(self.config.max_grad_norm);
                let o = &mut self.optimizer;
                for adam in [&mut o.actor, &mut o.critic, &mut o.log_std] {
                    adam.learning_rate = self.learning_rate;
                }
                o.actor.step(self.policy.actor.params_mut(), &self.grads.actor, self.threads);
                o.critic.step(self.policy.critic.params_mut(), &self.grads.critic, self.threads);
                o.log_std.step(&mut self.policy.log_std, &self.grads.log_std, 1);
                stats.surrogate_loss += terms.surrogate;
                stats.value_loss += terms.value;
                stats.entropy += terms.entropy;
                stats.kl += terms.kl;
                stats.clip_fraction += terms.clip_fraction;
                smoothness += terms.smoothness;
                curvature += terms.curvature;
                stats.grad_norm += norm as f64;
                count += 1.0;
            }
        }
        for x in [
            &mut stats.surrogate_loss,
            &mut stats.value_loss,
            &mut stats.entropy,
            &mut stats.kl,
            &mut stats.clip_fraction,
            &mut stats.grad_norm,
        ] {
            *x /= count;
        }
        stats.smoothness = (self.config.smoothness_coef > 0.0).then_some(smoothness / count);
        stats.curvature = (self.config.curvature_coef > 0.0).then_some(curvature / count);
        stats.learning_rate = self.learning_rate as f64;
        stats.action_std = self.policy.mean_std() as f64;
        self.storage.clear();
        stats
    }

    fn gather(&mut self, indices: &[usize]) {
        let (o, a) = (self.policy.observation_size(), self.policy.action_size());
        let (s, mb) = (&self.storage, &mut self.minibatch);
        mb.size = indices.len();
        mb.observations.clear();
        mb.actions.clear();
        mb.old_means.clear();
        mb.old_log_probs.clear();
        mb.old_values.clear();
        mb.advantages.clear();
        mb.returns.clear();
        mb.neighbour_means.clear();
        mb.neighbours.clear();
        mb.smoothness_weights.clear();
        let smooth = self.config.needs_neighbours();
        for &i in indices {
            if smooth {
                let [before, after] = s.neighbours_in_episode(i);
                let mut count = 0u8;
                for k in before.into_iter().chain(after) {
                    mb.neighbour_means.extend_from_slice(&s.means[k * a..(k + 1) * a]);
                    count += 1;
                }
                mb.neighbour_means.resize(mb.neighbour_means.len() + (2 - count as usize) * a, 0.0);
                mb.neighbours.push(count);
                mb.smoothness_weights.push(s.smoothness_weights[i]);
            }
            mb.actions.extend_from_slice(&s.actions[i * a..(i + 1) * a]);
            mb.old_means.extend_from_slice(&s.means[i * a..(i + 1) * a]);
            mb.old_log_probs.push(s.log_probs[i]);
            mb.old_values.push(s.values[i]);
            mb.advantages.push(s.advantages[i]);
            mb.returns.push(s.returns[i]);
        }
        // The observations are most of the bytes (540 floats a sample): copied by rows side by side.
        mb.observations.resize(indices.len() * o, 0.0);
        let copy = |(rows, out): (&[usize], &mut [f32])| {
            for (&i, row) in rows.iter().zip(out.chunks_exact_mut(o)) {
                row.copy_from_slice(&s.observations[i * o..(i + 1) * o]);
            }
        };
        if self.threads >= 2 {
            indices.par_chunks(GATHER_ROWS).zip(mb.observations.par_chunks_mut(GATHER_ROWS * o)).for_each(copy);
        } else {
            indices.chunks(GATHER_ROWS).zip(mb.observations.chunks_mut(GATHER_ROWS * o)).for_each(copy);
        }
        mb.old_log_std.clone_from(&self.rollout_log_std);
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;

    use super::*;

    #[test]
    fn the_learning_rate_falls_above_twice_the_target_kl_and_rises_below_half_of_it() {
        let target = 0.01;
        assert_eq!(adapted_learning_rate(3e-4, 0.021, target), 3e-4 / 1.5);
        assert_eq!(adapted_learning_rate(3e-4, 0.004, target), 3e-4 * 1.5);
        for inside in [0.0051, 0.01, 0.0199] {
            assert_eq!(adapted_learning_rate(3e-4, inside, target), 3e-4, "kl {inside} is within [target/2, 2 target]");
        }
        assert_eq!(adapted_learning_rate(3e-4, 0.0, target), 3e-4, "a zero KL (no policy change) moves nothing");
    }

    #[test]
    fn the_learning_rate_stays_within_its_range() {
        let (lowest, highest) = LEARNING_RATE_RANGE;
        assert_eq!(adapted_learning_rate(1.2e-5, 1.0, 0.01), lowest);
        assert_eq!(adapted_learning_rate(lowest, 1.0, 0.01), lowest);
        assert_eq!(adapted_learning_rate(8e-3, 1e-9, 0.01), highest);
        let mut rate = 1e-3;
        for _ in 0..100 {
            rate = adapted_learning_rate(rate, 1.0, 0.01);
        }
        assert_eq!(rate, lowest, "a KL that stays high pins the rate at the floor");
    }

    /// A learner over `envs` environments of 3 observations and 2 actions, one step per rollout.
    fn tiny_learner(envs: usize, schedule: Schedule) -> Ppo {
        let config = PpoConfig {
            steps_per_env: 1,
            minibatches: 1,
            epochs: 1,
            actor_hidden: vec![4],
            critic_hidden: vec![4],
            schedule,
            ..PpoConfig::default()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let policy = ActorCritic::new(3, 2, &config, &mut rng);
        Ppo::new(policy, config, envs, rng, 1)
    }

    #[test]
    fn a_truncated_episode_is_bootstrapped_with_the_value_of_its_final_observation() {
        let mut ppo = tiny_learner(3, Schedule::Adaptive);
        let observations = [0.1, -0.2, 0.3, 1.0, 0.5, -0.5, -1.0, 0.0, 2.0];
        let mut actions = [0.0; 6];
        ppo.act(&observations, &mut actions);
        // Environment 0 was cut by the time limit, 1 crashed, 2 crashed on its last allowed step.
        let final_observations = [0.4, 0.4, -0.3, 9.0, 9.0, 9.0, 7.0, 7.0, 7.0];
        ppo.process_step(&[1.0, 1.0, 1.0], &[false, true, true], &[true, false, true], &final_observations);

        let mut normalized = Vec::new();
        ppo.policy.normalizer.normalize(&final_observations[..3], &mut normalized);
        let value = ppo.policy.critic.forward(&normalized, 1, &mut Workspace::default(), 1)[0];
        assert!(value.abs() > 1e-4, "the test needs a critic that does not answer zero, got {value}");
        let rewards = &ppo.storage.rewards;
        assert!((rewards[0] - (1.0 + ppo.config.gamma * value)).abs() < 1e-6, "{} vs value {value}", rewards[0]);
        assert_eq!(rewards[1], 1.0, "a terminated episode has no future to bootstrap");
        assert_eq!(rewards[2], 1.0, "terminated wins over truncated");
        assert_eq!(ppo.storage.dones, [true, true, true]);
    }

    #[test]
    fn an_update_applies_the_schedule_only_when_adaptive() {
        for schedule in [Schedule::Adaptive, Schedule::Fixed] {
            let mut ppo = tiny_learner(8, schedule);
            let observations: Vec<f32> = (0..24).map(|k| (k as f32 * 0.37).sin()).collect();
            let mut actions = vec![0.0; 16];
            ppo.act(&observations, &mut actions);
            let rewards: Vec<f32> = (0..8).map(|k| k as f32 - 3.5).collect();
            ppo.process_step(&rewards, &[false; 8], &[false; 8], &observations);
            ppo.finish_rollout(&observations);
            let stats = ppo.update();
            let expected = match schedule {
                // One minibatch: the rate moves at most one step of 1.5 from its start.
                Schedule::Adaptive => adapted_learning_rate(ppo.config.learning_rate, stats.kl, ppo.config.desired_kl),
                Schedule::Fixed => ppo.config.learning_rate,
            };
            assert_eq!(ppo.learning_rate, expected, "{schedule:?}: kl {}", stats.kl);
            assert!(ppo.storage.step() == 0, "the update clears the rollout");
        }
    }
}
