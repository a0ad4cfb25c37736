//! The PPO loss and its gradients (rsl_rl's `ppo.py` update maths): the clipped surrogate, the
//! (optionally clipped) value loss and the entropy bonus of one minibatch, differentiated by hand
//! through the actor, the critic and the log-std, and checked against finite differences below. A
//! minibatch is computed in [`CHUNKS`] fixed chunks whose gradients are added in a fixed order, so
//! the result is the same on any number of threads (and, through [`crate::fixed_matmul`], any CPU).

use std::ops::Range;

use rayon::prelude::*;

use crate::actor_critic::{ActorCritic, HALF_LN_2PI};
use crate::adam::PARAMETER_SLICE;
use crate::config::{PpoConfig, SmoothnessNorm};
use crate::mlp::Workspace;

/// Gradients of the loss, shaped like the parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct Gradients {
    pub actor: Vec<f32>,
    pub critic: Vec<f32>,
    pub log_std: Vec<f32>,
}

impl Gradients {
    pub fn zeros(policy: &ActorCritic) -> Self {
        Self {
            actor: vec![0.0; policy.actor.params().len()],
            critic: vec![0.0; policy.critic.params().len()],
            log_std: vec![0.0; policy.log_std.len()],
        }
    }

    /// Sets each gradient to the sum of `parts`' (`((p0 + p1) + p2) + ...`, in the order given), the
    /// parameters shared out over `threads` threads in slices: each element's sum is the same in any slice.
    fn add_in_order(&mut self, parts: &[&Gradients], threads: usize) {
        let (first, rest) = parts.split_first().expect("at least one chunk");
        for (which, out) in [&mut self.actor, &mut self.critic, &mut self.log_std].into_iter().enumerate() {
            let sum_slice = |start: usize, out: &mut [f32]| {
                out.copy_from_slice(&first.tensors()[which][start..start + out.len()]);
                for part in rest {
                    for (o, x) in out.iter_mut().zip(&part.tensors()[which][start..]) {
                        *o += x;
                    }
                }
            };
            if threads >= 2 {
                out.par_chunks_mut(PARAMETER_SLICE)
                    .enumerate()
                    .for_each(|(s, slice)| sum_slice(s * PARAMETER_SLICE, slice));
            } else {
                sum_slice(0, out);
            }
        }
    }

    /// The actor's, the critic's and the log-std's gradients, in that order.
    fn tensors(&self) -> [&[f32]; 3] {
        [&self.actor, &self.critic, &self.log_std]
    }

    /// Scales all gradients together so their global L2 norm is at most `max_norm`; returns the norm
    /// before clipping.
    pub fn clip_global_norm(&mut self, max_norm: f32) -> f32 {
        let squares: f64 = [&self.actor, &self.critic, &self.log_std]
            .iter()
            .flat_map(|g| g.iter())
            .map(|&g| (g as f64) * (g as f64))
            .sum();
        let norm = squares.sqrt() as f32;
        if norm > max_norm {
            let scale = max_norm / (norm + 1e-6);
            for g in [&mut self.actor, &mut self.critic, &mut self.log_std] {
                g.iter_mut().for_each(|x| *x *= scale);
            }
        }
        norm
    }
}

/// One minibatch of samples, gathered from the rollout.
#[derive(Debug, Clone, Default)]
pub struct Minibatch {
    pub size: usize,
    pub observations: Vec<f32>,
    pub actions: Vec<f32>,
    pub old_log_probs: Vec<f32>,
    pub old_means: Vec<f32>,
    /// log sigma of the policy that collected the samples.
    pub old_log_std: Vec<f32>,
    pub old_values: Vec<f32>,
    pub advantages: Vec<f32>,
    pub returns: Vec<f32>,
    /// The collected means of each sample's neighbours in time (the step before and after in the same
    /// episode and rollout), `neighbours[i]` of them from `neighbour_means[i * 2 * action_size]` on.
    /// Filled only when [`PpoConfig::needs_neighbours`].
    pub neighbour_means: Vec<f32>,
    pub neighbours: Vec<u8>,
    /// Each sample's weight of the smoothness term, as the environment gave it
    /// ([`crate::VecEnv::smoothness_weights`]); empty when the environment gives none (every weight 1).
    pub smoothness_weights: Vec<f32>,
}

/// Below this gap (in action units) [`SmoothnessNorm::Euclidean`] turns quadratic, sqrt(|gap|^2 + s^2) - s,
/// so that its gradient is defined at zero; 0.01 is about a degree of flap target.
pub const EUCLIDEAN_SMOOTHING: f32 = 0.01;

/// The loss of one minibatch and its parts.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LossTerms {
    pub surrogate: f64,
    pub value: f64,
    /// Mean entropy of the action distribution.
    pub entropy: f64,
    /// Mean KL(pi_old || pi) over the minibatch.
    pub kl: f64,
    /// Fraction of samples whose ratio lies outside [1 - clip, 1 + clip].
    pub clip_fraction: f64,
    /// Mean over samples of the squared distance of the actor's mean to its neighbours' collected means,
    /// each sample's distance weighted by its smoothness weight.
    pub smoothness: f64,
    /// Mean over samples of the squared distance of the actor's mean to the midpoint of its two
    /// neighbours' collected means (0 for a sample without both).
    pub curvature: f64,
    /// surrogate + value_loss_coef value - entropy_coef entropy + smoothness_coef smoothness
    /// + curvature_coef curvature.
    pub total: f64,
}

/// How many chunks a minibatch is split into, whatever the thread count: the chunks' forward and
/// backward passes run side by side, and their gradients and loss sums are added in chunk order. A
/// constant, so that 1, 2 or 16 threads compute the same bits. More threads than chunks share each
/// chunk's products by rows, which changes no element's arithmetic. Each chunk holds a whole gradient,
/// and adding them costs memory traffic: 4 is where 2 cores lose least (16 chunks: 15% slower updates).
pub const CHUNKS: usize = 4;

/// Scratch buffers of the loss computation, one set per chunk.
#[derive(Debug, Clone, Default)]
pub struct LossScratch {
    chunks: Vec<ChunkScratch>,
}

/// One chunk's buffers and results: its gradients and its loss sums (not yet means).
#[derive(Debug, Clone)]
struct ChunkScratch {
    actor: Workspace,
    critic: Workspace,
    d_mean: Vec<f32>,
    d_value: Vec<f32>,
    grads: Gradients,
    sums: LossTerms,
}

/// The rows of chunk `chunk` of `n` samples: contiguous, as even as integers allow.
pub fn chunk_rows(chunk: usize, n: usize) -> Range<usize> {
    chunk * n / CHUNKS..(chunk + 1) * n / CHUNKS
}

/// The loss of `batch` under `policy` and its gradient with respect to every parameter (written into
/// `grads`). The maths of PPO in one function, checked against finite differences in the tests.
/// The samples are split into [`CHUNKS`] chunks computed side by side on `threads` threads (in the
/// caller's rayon pool), then added in chunk order: the result does not depend on `threads`.
pub fn loss_and_gradients(
    policy: &ActorCritic,
    config: &PpoConfig,
    batch: &Minibatch,
    scratch: &mut LossScratch,
    grads: &mut Gradients,
    threads: usize,
) -> LossTerms {
    scratch.chunks.resize_with(CHUNKS, || ChunkScratch {
        actor: Workspace::default(),
        critic: Workspace::default(),
        d_mean: Vec::new(),
        d_value: Vec::new(),
        grads: Gradients::zeros(policy),
        sums: LossTerms::default(),
    });
    // Each chunk's actor and critic are independent: with threads to spare they run side by side too,
    // 2 x CHUNKS tasks, and what threads remain share each task's products by rows.
    let side_by_side = threads >= 2;
    let inner = (threads / if side_by_side { 2 * CHUNKS } else { CHUNKS }).max(1);
    let one_chunk = |(index, chunk): (usize, &mut ChunkScratch)| {
        let rows = chunk_rows(index, batch.size);
        let ChunkScratch { actor, critic, d_mean, d_value, grads, sums } = chunk;
        let Gradients { actor: actor_grads, critic: critic_grads, log_std: log_std_grads } = grads;
        let policy_rows = rows.clone();
        let policy_part =
            move || policy_loss(policy, config, batch, policy_rows, actor, d_mean, actor_grads, log_std_grads, inner);
        let value_part = move || value_loss(policy, config, batch, rows, critic, d_value, critic_grads, inner);
        let (policy_sums, value_sum) =
            if side_by_side { rayon::join(policy_part, value_part) } else { (policy_part(), value_part()) };
        *sums = LossTerms { value: value_sum, ..policy_sums };
    };
    if threads >= 2 {
        scratch.chunks.par_iter_mut().enumerate().with_max_len(1).for_each(one_chunk);
    } else {
        scratch.chunks.iter_mut().enumerate().for_each(one_chunk);
    }
    let parts: Vec<&Gradients> = scratch.chunks.iter().map(|c| &c.grads).collect();
    grads.add_in_order(&parts, threads);
    // Entropy of a diagonal Gaussian: sum_j (log sigma_j + 1/2 + ln(2 pi)/2), the same for every sample.
    for g in grads.log_std.iter_mut() {
        *g -= config.entropy_coef;
    }
    let mut terms = LossTerms::default();
    for sums in scratch.chunks.iter().map(|c| &c.sums) {
        terms.surrogate += sums.surrogate;
        terms.value += sums.value;
        terms.kl += sums.kl;
        terms.clip_fraction += sums.clip_fraction;
        terms.smoothness += sums.smoothness;
        terms.curvature += sums.curvature;
    }
    let n = batch.size as f64;
    for mean in [
        &mut terms.surrogate,
        &mut terms.value,
        &mut terms.kl,
        &mut terms.clip_fraction,
        &mut terms.smoothness,
        &mut terms.curvature,
    ] {
        *mean /= n;
    }
    let log_std_sum: f32 = policy.log_std.iter().sum();
    terms.entropy = (log_std_sum + policy.action_size() as f32 * (0.5 + HALF_LN_2PI)) as f64;
    terms.total = terms.surrogate + config.value_loss_coef as f64 * terms.value
        - config.entropy_coef as f64 * terms.entropy
        + config.smoothness_coef as f64 * terms.smoothness
        + config.curvature_coef as f64 * terms.curvature;
    terms
}

/// The clipped surrogate of the samples `rows` (its sum, not yet divided by the minibatch size), and
/// its gradients for the actor and the log-std (already divided); the entropy is added by the caller.
#[allow(clippy::too_many_arguments)]
fn policy_loss(
    policy: &ActorCritic,
    config: &PpoConfig,
    batch: &Minibatch,
    rows: Range<usize>,
    workspace: &mut Workspace,
    d_mean: &mut Vec<f32>,
    actor_grads: &mut [f32],
    log_std_grads: &mut [f32],
    threads: usize,
) -> LossTerms {
    let (n, a_size, o_size) = (rows.len(), policy.action_size(), policy.observation_size());
    let inv_n = 1.0 / batch.size as f32;
    let std: Vec<f32> = policy.log_std.iter().map(|&s| libm::expf(s)).collect();
    let inv_var: Vec<f32> = std.iter().map(|s| 1.0 / (s * s)).collect();
    let old_var: Vec<f32> = batch.old_log_std.iter().map(|&s| libm::expf(2.0 * s)).collect();
    let log_std_sum: f32 = policy.log_std.iter().sum();
    let eps = config.clip;

    let observations = &batch.observations[rows.start * o_size..rows.end * o_size];
    let means = policy.actor.forward(observations, n, workspace, threads);
    d_mean.resize(n * a_size, 0.0);
    log_std_grads.iter_mut().for_each(|g| *g = 0.0);
    let mut terms = LossTerms::default();
    for (local, i) in rows.enumerate() {
        let row = i * a_size..(i + 1) * a_size;
        let mu = &means[local * a_size..(local + 1) * a_size];
        let (action, old_mu) = (&batch.actions[row.clone()], &batch.old_means[row]);
        let mut log_prob = -log_std_sum - a_size as f32 * HALF_LN_2PI;
        let mut kl = 0.0f32;
        for j in 0..a_size {
            let diff = action[j] - mu[j];
            log_prob -= 0.5 * diff * diff * inv_var[j];
            let mean_shift = old_mu[j] - mu[j];
            kl += policy.log_std[j] - batch.old_log_std[j] + (old_var[j] + mean_shift * mean_shift) * 0.5 * inv_var[j]
                - 0.5;
        }
        let ratio = libm::expf(log_prob - batch.old_log_probs[i]);
        let advantage = batch.advantages[i];
        let unclipped = -advantage * ratio;
        let clipped = -advantage * ratio.clamp(1.0 - eps, 1.0 + eps);
        terms.surrogate += unclipped.max(clipped) as f64;
        terms.kl += kl as f64;
        if (ratio - 1.0).abs() > eps {
            terms.clip_fraction += 1.0;
        }
        // d(surrogate)/d(log pi): the unclipped branch carries the gradient; the clipped one is flat.
        let d_log_prob = if unclipped >= clipped { -advantage * ratio * inv_n } else { 0.0 };
        for j in 0..a_size {
            let diff = action[j] - mu[j];
            d_mean[local * a_size + j] = d_log_prob * diff * inv_var[j];
            log_std_grads[j] += d_log_prob * (diff * diff * inv_var[j] - 1.0);
        }
        if config.smoothness_coef > 0.0 {
            let weight = batch.smoothness_weights.get(i).copied().unwrap_or(1.0);
            let neighbours = batch.neighbour_means[i * 2 * a_size..].chunks_exact(a_size);
            for neighbour in neighbours.take(batch.neighbours[i] as usize) {
                // Each action's gap is scaled by its share (1 for every action unless
                // `smoothness_action_scale` says otherwise; x 1 changes no bit).
                let gap = |j: usize| (mu[j] - neighbour[j]) * config.smoothness_scale(j);
                match config.smoothness_norm {
                    SmoothnessNorm::Squared => {
                        for j in 0..a_size {
                            let gap = gap(j);
                            terms.smoothness += (weight * gap * gap) as f64;
                            d_mean[local * a_size + j] +=
                                2.0 * config.smoothness_coef * weight * gap * config.smoothness_scale(j) * inv_n;
                        }
                    }
                    SmoothnessNorm::Euclidean => {
                        // sqrt(|gap|^2 + s^2) - s and its gradient gap / sqrt(|gap|^2 + s^2).
                        let squared: f32 = (0..a_size).map(|j| gap(j) * gap(j)).sum();
                        let norm = (squared + EUCLIDEAN_SMOOTHING * EUCLIDEAN_SMOOTHING).sqrt();
                        terms.smoothness += (weight * (norm - EUCLIDEAN_SMOOTHING)) as f64;
                        for j in 0..a_size {
                            d_mean[local * a_size + j] +=
                                config.smoothness_coef * weight * gap(j) * config.smoothness_scale(j) / norm * inv_n;
                        }
                    }
                }
            }
        }
        if config.curvature_coef > 0.0 && batch.neighbours[i] == 2 {
            // The step before and the step after, in that order: mu - (before + after) / 2.
            let (before, after) = batch.neighbour_means[i * 2 * a_size..(i + 1) * 2 * a_size].split_at(a_size);
            for j in 0..a_size {
                let bend = mu[j] - 0.5 * (before[j] + after[j]);
                terms.curvature += (bend * bend) as f64;
                d_mean[local * a_size + j] += 2.0 * config.curvature_coef * bend * inv_n;
            }
        }
    }
    policy.actor.backward(workspace, observations, d_mean, actor_grads, threads);
    terms
}

/// The (clipped) value loss of the samples `rows` (its sum, not yet divided by the minibatch size)
/// and its gradient for the critic, scaled by the value-loss coefficient.
#[allow(clippy::too_many_arguments)]
fn value_loss(
    policy: &ActorCritic,
    config: &PpoConfig,
    batch: &Minibatch,
    rows: Range<usize>,
    workspace: &mut Workspace,
    d_value: &mut Vec<f32>,
    critic_grads: &mut [f32],
    threads: usize,
) -> f64 {
    let (n, o_size) = (rows.len(), policy.observation_size());
    let (inv_n, eps) = (1.0 / batch.size as f32, config.clip);
    let observations = &batch.observations[rows.start * o_size..rows.end * o_size];
    let values = policy.critic.forward(observations, n, workspace, threads);
    d_value.resize(n, 0.0);
    let mut total = 0.0f64;
    for (local, i) in rows.enumerate() {
        let (v, target, old) = (values[local], batch.returns[i], batch.old_values[i]);
        let error = v - target;
        let (loss, d) = if config.clipped_value_loss {
            let clipped = old + (v - old).clamp(-eps, eps);
            let clipped_error = clipped - target;
            if error * error >= clipped_error * clipped_error {
                (error * error, 2.0 * error)
            } else {
                let inside = ((v - old).abs() < eps) as u8 as f32;
                (clipped_error * clipped_error, 2.0 * clipped_error * inside)
            }
        } else {
            (error * error, 2.0 * error)
        };
        total += loss as f64;
        d_value[local] = config.value_loss_coef * d * inv_n;
    }
    policy.critic.backward(workspace, observations, d_value, critic_grads, threads);
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A small policy and a minibatch whose ratios spread over both sides of the clip range.
    fn setup(clipped_value_loss: bool) -> (ActorCritic, PpoConfig, Minibatch) {
        let config = PpoConfig {
            actor_hidden: vec![8, 6],
            critic_hidden: vec![7],
            clipped_value_loss,
            entropy_coef: 0.05,
            value_loss_coef: 0.7,
            init_noise_std: 0.6,
            ..PpoConfig::default()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut policy = ActorCritic::new(5, 3, &config, &mut rng);
        // A larger output layer than the default 0.01 gain, so the actor's gradients are not tiny.
        for p in policy.actor.params_mut() {
            *p *= 1.0 + rng.random_range(0.0..3.0f32);
        }
        let n = 16;
        let observations: Vec<f32> = (0..n * 5).map(|_| rng.random_range(-2.0..2.0)).collect();
        let mut scratch = Workspace::default();
        let means = policy.actor.forward(&observations, n, &mut scratch, 1).to_vec();
        let mut critic_ws = Workspace::default();
        let values = policy.critic.forward(&observations, n, &mut critic_ws, 1).to_vec();
        let std = 0.6f32;
        let actions: Vec<f32> = means.iter().map(|m| m + std * rng.random_range(-1.5..1.5)).collect();
        let log_prob = |i: usize| -> f32 {
            (0..3)
                .map(|j| -0.5 * ((actions[i * 3 + j] - means[i * 3 + j]) / std).powi(2) - std.ln() - HALF_LN_2PI)
                .sum()
        };
        let old_log_probs: Vec<f32> = (0..n).map(|i| log_prob(i) + rng.random_range(-0.5..0.5)).collect();
        let old_means: Vec<f32> = means.iter().map(|m| m + rng.random_range(-0.2..0.2)).collect();
        let old_values: Vec<f32> = values.iter().map(|v| v + rng.random_range(-0.5..0.5)).collect();
        let batch = Minibatch {
            size: n,
            observations,
            actions,
            old_log_probs,
            old_means,
            old_log_std: vec![0.7f32.ln(); 3],
            old_values,
            advantages: (0..n).map(|_| rng.random_range(-2.0..2.0)).collect(),
            returns: (0..n).map(|_| rng.random_range(-1.0..1.0)).collect(),
            neighbour_means: (0..n * 2 * 3).map(|_| rng.random_range(-1.0..1.0)).collect(),
            neighbours: (0..n).map(|i| (i % 3) as u8).collect(),
            smoothness_weights: Vec::new(),
        };
        (policy, config, batch)
    }

    fn loss(policy: &ActorCritic, config: &PpoConfig, batch: &Minibatch) -> f64 {
        let mut grads = Gradients::zeros(policy);
        loss_and_gradients(policy, config, batch, &mut LossScratch::default(), &mut grads, 1).total
    }

    fn param_mut<'a>(policy: &'a mut ActorCritic, which: &str, i: usize) -> &'a mut f32 {
        if which == "actor" { &mut policy.actor.params_mut()[i] } else { &mut policy.critic.params_mut()[i] }
    }

    /// Central differences, relative error per tensor, as for the MLP.
    fn check(clipped_value_loss: bool, smoothness_coef: f32, weighted: bool) {
        check_with(clipped_value_loss, smoothness_coef, SmoothnessNorm::Squared, weighted, Vec::new())
    }

    /// As `check`, with the smoothness measured by `norm` and each action's share `shares` (empty: all 1).
    fn check_with(
        clipped_value_loss: bool,
        smoothness_coef: f32,
        norm: SmoothnessNorm,
        weighted: bool,
        shares: Vec<f32>,
    ) {
        let (policy, mut config, mut batch) = setup(clipped_value_loss);
        config.smoothness_coef = smoothness_coef;
        config.smoothness_norm = norm;
        config.smoothness_action_scale = shares;
        if weighted {
            batch.smoothness_weights = (0..batch.size).map(|i| [0.0, 0.3, 1.0][i % 3]).collect();
        }
        check_gradients(policy, &config, &batch);
    }

    /// The analytic gradients of `config`'s loss on `batch` against central differences.
    fn check_gradients(mut policy: ActorCritic, config: &PpoConfig, batch: &Minibatch) {
        let clipped_value_loss = config.clipped_value_loss;
        let (config, batch) = (config.clone(), batch.clone());
        let mut grads = Gradients::zeros(&policy);
        let terms = loss_and_gradients(&policy, &config, &batch, &mut LossScratch::default(), &mut grads, 1);
        assert!(
            terms.clip_fraction > 0.1 && terms.clip_fraction < 0.9,
            "both sides of the clip: {}",
            terms.clip_fraction
        );
        let eps = 2e-3f32;
        let compare = |name: &str, analytic: &[f32], numeric: &[f64]| {
            let worst = analytic
                .iter()
                .zip(numeric)
                .map(|(&a, &n)| (n - a as f64).abs() / (2e-3 + n.abs().max((a as f64).abs())))
                .fold(0.0, f64::max);
            assert!(worst < 3e-2, "{name} (clipped value loss {clipped_value_loss}): worst relative error {worst:.2e}");
        };
        let mut numeric = Vec::new();
        for i in 0..policy.log_std.len() {
            let original = policy.log_std[i];
            policy.log_std[i] = original + eps;
            let up = loss(&policy, &config, &batch);
            policy.log_std[i] = original - eps;
            let down = loss(&policy, &config, &batch);
            policy.log_std[i] = original;
            numeric.push((up - down) / (2.0 * eps as f64));
        }
        compare("log_std", &grads.log_std, &numeric);
        for which in ["actor", "critic"] {
            let tensors =
                if which == "actor" { policy.actor.tensors().to_vec() } else { policy.critic.tensors().to_vec() };
            for tensor in tensors {
                let mut numeric = Vec::new();
                for i in tensor.range.clone() {
                    let original = *param_mut(&mut policy, which, i);
                    *param_mut(&mut policy, which, i) = original + eps;
                    let up = loss(&policy, &config, &batch);
                    *param_mut(&mut policy, which, i) = original - eps;
                    let down = loss(&policy, &config, &batch);
                    *param_mut(&mut policy, which, i) = original;
                    numeric.push((up - down) / (2.0 * eps as f64));
                }
                let analytic = if which == "actor" {
                    &grads.actor[tensor.range.clone()]
                } else {
                    &grads.critic[tensor.range.clone()]
                };
                compare(&format!("{which}.{}", tensor.name), analytic, &numeric);
            }
        }
    }

    #[test]
    fn ppo_loss_gradients_match_finite_differences() {
        check(true, 0.0, false);
        check(false, 0.0, false);
        check(true, 0.7, false);
        check(false, 0.7, true);
        check_with(true, 0.7, SmoothnessNorm::Euclidean, false, Vec::new());
        check_with(false, 0.7, SmoothnessNorm::Euclidean, true, Vec::new());
    }

    /// Each action's share scales its gap before the distance is taken, in the loss and its gradient.
    #[test]
    fn the_loss_gradients_match_finite_differences_with_per_action_smoothness_shares() {
        for norm in [SmoothnessNorm::Squared, SmoothnessNorm::Euclidean] {
            check_with(false, 0.7, norm, false, vec![1.0, 0.0, 2.5]);
        }
    }

    /// The curvature term beside the smoothness, weighted and with shares (which it ignores).
    #[test]
    fn the_loss_gradients_match_finite_differences_with_the_curvature_term() {
        for clipped in [false, true] {
            let (policy, mut config, mut batch) = setup(clipped);
            config.curvature_coef = 0.7;
            check_gradients(policy.clone(), &config, &batch);
            config.smoothness_coef = 0.3;
            config.smoothness_action_scale = vec![1.0, 0.0, 2.5];
            batch.smoothness_weights = (0..batch.size).map(|i| [0.0, 0.3, 1.0][i % 3]).collect();
            check_gradients(policy, &config, &batch);
        }
    }

    /// The curvature prices a fast stroke above a slow one that moves its targets as fast (the same
    /// first difference, which is all the squared smoothness sees), counts only samples with both
    /// neighbours, and sits in the total at its coefficient.
    #[test]
    fn the_curvature_prices_a_fast_stroke_above_a_slow_one_of_the_same_speed() {
        let (policy, mut config, mut batch) = smoothness_alone();
        batch.neighbours.iter_mut().for_each(|n| *n = 2);
        let means = policy.actor.forward(&batch.observations, batch.size, &mut Workspace::default(), 1).to_vec();
        // Each mean sits on a sine of amplitude `amplitude` and `cycles` cycles per 50 steps (a 50 Hz policy),
        // at the phase of its sample; the neighbours are the sine one step before and after.
        let terms = |amplitude: f32, hz: f32, config: &PpoConfig, batch: &mut Minibatch| {
            let step = std::f32::consts::TAU * hz / 50.0;
            for i in 0..batch.size {
                let phase = i as f32 * 0.37;
                for j in 0..3 {
                    let mean = means[i * 3 + j];
                    let at = |k: f32| amplitude * (phase + k * step).sin();
                    batch.neighbour_means[i * 6 + j] = mean + at(-1.0) - at(0.0);
                    batch.neighbour_means[i * 6 + 3 + j] = mean + at(1.0) - at(0.0);
                }
            }
            let mut grads = Gradients::zeros(&policy);
            loss_and_gradients(&policy, config, batch, &mut LossScratch::default(), &mut grads, 1)
        };
        config.value_loss_coef = 0.0;
        config.curvature_coef = 1.0;
        // The same amplitude x frequency (the targets' speed), at 4 and at 6 Hz.
        let slow = terms(0.6, 4.0, &config, &mut batch);
        let fast = terms(0.4, 6.0, &config, &mut batch);
        assert!((fast.smoothness / slow.smoothness - 1.0).abs() < 0.1, "{} / {}", fast.smoothness, slow.smoothness);
        assert!(fast.curvature > 1.8 * slow.curvature, "{} against {}", fast.curvature, slow.curvature);
        assert!((fast.total - fast.smoothness - fast.curvature).abs() < 1e-9, "{fast:?}");
        // Without both neighbours a sample has no curvature.
        batch.neighbours.iter_mut().for_each(|n| *n = 1);
        assert_eq!(terms(0.4, 6.0, &config, &mut batch).curvature, 0.0);
        // Off: none, and the total is the smoothness alone.
        config.curvature_coef = 0.0;
        batch.neighbours.iter_mut().for_each(|n| *n = 2);
        let off = terms(0.4, 6.0, &config, &mut batch);
        assert_eq!((off.curvature, off.total), (0.0, off.smoothness));
    }

    /// `setup`'s policy and batch with the smoothness term alone in the loss: no advantage, no entropy,
    /// the smoothness at coefficient 1.
    fn smoothness_alone() -> (ActorCritic, PpoConfig, Minibatch) {
        let (policy, mut config, mut batch) = setup(false);
        batch.advantages.iter_mut().for_each(|a| *a = 0.0);
        config.entropy_coef = 0.0;
        config.smoothness_coef = 1.0;
        (policy, config, batch)
    }

    /// An action whose share is 0 is not pulled at all; the others are pulled as without shares when
    /// the distance is squared (each action's term is its own).
    #[test]
    fn an_action_with_no_smoothness_share_is_not_pulled_towards_its_neighbours() {
        let (policy, mut config, batch) = smoothness_alone();
        let output_bias_gradient = |config: &PpoConfig| {
            let mut grads = Gradients::zeros(&policy);
            loss_and_gradients(&policy, config, &batch, &mut LossScratch::default(), &mut grads, 1);
            let bias = policy.actor.tensors().last().expect("an output bias").range.clone();
            grads.actor[bias].to_vec()
        };
        let all = output_bias_gradient(&config);
        config.smoothness_action_scale = vec![1.0, 0.0, 1.0];
        let shared = output_bias_gradient(&config);
        assert!(all[1].abs() > 1e-6, "the smoothness pulls action 1 without shares: {all:?}");
        assert_eq!(shared[1], 0.0, "{shared:?}");
        assert_eq!((shared[0], shared[2]), (all[0], all[2]));
    }

    /// The squared distance's pull on the mean fades with the gap; the Euclidean one's does not, which
    /// is what can make holding the wings still (no flapping cycle) worth more than a small flap.
    #[test]
    fn the_euclidean_smoothness_pulls_as_hard_on_a_small_gap_as_on_a_large_one() {
        let (policy, config, mut batch) = smoothness_alone();
        batch.neighbours.iter_mut().for_each(|n| *n = 1);
        // The size of the gradient on the actor's output bias when every neighbour sits `gap` above the mean.
        let pull = |norm: SmoothnessNorm, gap: f32| {
            let mut config = config.clone();
            config.smoothness_norm = norm;
            let mut batch = batch.clone();
            let means = policy.actor.forward(&batch.observations, batch.size, &mut Workspace::default(), 1).to_vec();
            for i in 0..batch.size {
                for j in 0..3 {
                    batch.neighbour_means[i * 6 + j] = means[i * 3 + j] + gap;
                }
            }
            let mut grads = Gradients::zeros(&policy);
            let terms = loss_and_gradients(&policy, &config, &batch, &mut LossScratch::default(), &mut grads, 1);
            let bias = policy.actor.tensors().last().expect("an output bias").range.clone();
            let size: f32 = grads.actor[bias].iter().map(|g| g * g).sum::<f32>().sqrt();
            (size, terms.smoothness)
        };
        let (squared_large, _) = pull(SmoothnessNorm::Squared, 0.5);
        let (squared_small, _) = pull(SmoothnessNorm::Squared, 0.05);
        let (euclidean_large, distance_large) = pull(SmoothnessNorm::Euclidean, 0.5);
        let (euclidean_small, distance_small) = pull(SmoothnessNorm::Euclidean, 0.05);
        assert!((squared_small / squared_large - 0.1).abs() < 0.01, "{squared_small} / {squared_large}");
        assert!(euclidean_small / euclidean_large > 0.9, "{euclidean_small} / {euclidean_large}");
        // The distance itself: |gap| sqrt(3) less the smoothing, per neighbour.
        let expected = |gap: f64| (3.0 * gap * gap + 1e-4f64).sqrt() - 0.01;
        assert!((distance_large - expected(0.5)).abs() < 1e-4, "{distance_large}");
        assert!((distance_small - expected(0.05)).abs() < 1e-4, "{distance_small}");
    }

    #[test]
    fn the_smoothness_term_pulls_the_mean_towards_its_neighbours_and_ignores_missing_ones() {
        let (mut policy, mut config, mut batch) = setup(false);
        batch.advantages.iter_mut().for_each(|a| *a = 0.0);
        config.entropy_coef = 0.0;
        let distance = |policy: &ActorCritic, config: &PpoConfig, batch: &Minibatch| {
            let mut grads = Gradients::zeros(policy);
            loss_and_gradients(policy, config, batch, &mut LossScratch::default(), &mut grads, 1)
        };
        // Off: no term, whatever the neighbours.
        assert_eq!(distance(&policy, &config, &batch).smoothness, 0.0);
        config.smoothness_coef = 1.0;
        let before = distance(&policy, &config, &batch);
        assert!(before.smoothness > 0.0);
        // Only the first neighbours[i] means count: garbage after them changes nothing.
        let mut padded = batch.clone();
        for i in 0..padded.size {
            let start = i * 6 + padded.neighbours[i] as usize * 3;
            padded.neighbour_means[start..(i + 1) * 6].iter_mut().for_each(|m| *m = 1e6);
        }
        assert_eq!(distance(&policy, &config, &padded), before);
        // Gradient steps on the actor bring the means closer to their neighbours.
        for _ in 0..20 {
            let mut grads = Gradients::zeros(&policy);
            loss_and_gradients(&policy, &config, &batch, &mut LossScratch::default(), &mut grads, 1);
            for (p, g) in policy.actor.params_mut().iter_mut().zip(&grads.actor) {
                *p -= 0.05 * g;
            }
        }
        let after = distance(&policy, &config, &batch);
        assert!(after.smoothness < 0.9 * before.smoothness, "{} -> {}", before.smoothness, after.smoothness);
    }

    #[test]
    fn a_sample_weighted_zero_feels_no_smoothness_and_weights_of_one_change_nothing() {
        let (policy, mut config, batch) = setup(false);
        let run = |config: &PpoConfig, batch: &Minibatch| {
            let mut grads = Gradients::zeros(&policy);
            let terms = loss_and_gradients(&policy, config, batch, &mut LossScratch::default(), &mut grads, 1);
            (terms, grads)
        };
        config.smoothness_coef = 0.0;
        let (off, off_grads) = run(&config, &batch);
        config.smoothness_coef = 1.0;
        let (unweighted, unweighted_grads) = run(&config, &batch);
        let ones = Minibatch { smoothness_weights: vec![1.0; batch.size], ..batch.clone() };
        let (terms, grads) = run(&config, &ones);
        assert_eq!(terms, unweighted);
        assert_eq!(grads.actor, unweighted_grads.actor);
        // Weight 0 on every sample: the loss and its gradients are those without the term.
        let zeros = Minibatch { smoothness_weights: vec![0.0; batch.size], ..batch.clone() };
        let (terms, grads) = run(&config, &zeros);
        assert_eq!(terms.smoothness, 0.0);
        assert_eq!(terms.total, off.total);
        assert_eq!(grads.actor, off_grads.actor);
        // Half the samples at 0: the term is what the other half carries.
        let half = Minibatch { smoothness_weights: (0..batch.size).map(|i| (i % 2) as f32).collect(), ..batch.clone() };
        let (terms, _) = run(&config, &half);
        assert!(terms.smoothness > 0.0 && terms.smoothness < unweighted.smoothness, "{}", terms.smoothness);
    }

    #[test]
    fn two_threads_give_the_same_loss_and_gradients_as_one() {
        let (policy, config, batch) = setup(true);
        let (mut one, mut two) = (Gradients::zeros(&policy), Gradients::zeros(&policy));
        let a = loss_and_gradients(&policy, &config, &batch, &mut LossScratch::default(), &mut one, 1);
        let b = loss_and_gradients(&policy, &config, &batch, &mut LossScratch::default(), &mut two, 2);
        assert_eq!(a, b);
        assert_eq!(one, two);
    }

    #[test]
    fn a_zero_advantage_batch_only_moves_the_value_and_the_entropy() {
        let (policy, config, mut batch) = setup(false);
        batch.advantages.iter_mut().for_each(|a| *a = 0.0);
        let mut grads = Gradients::zeros(&policy);
        loss_and_gradients(&policy, &config, &batch, &mut LossScratch::default(), &mut grads, 1);
        assert!(grads.actor.iter().all(|&g| g == 0.0));
        assert!(grads.log_std.iter().all(|&g| (g + config.entropy_coef).abs() < 1e-7), "entropy pushes sigma up");
        assert!(grads.critic.iter().any(|&g| g != 0.0));
    }

    #[test]
    fn a_positive_advantage_raises_the_probability_of_its_action() {
        let (mut policy, mut config, mut batch) = setup(false);
        config.entropy_coef = 0.0;
        config.value_loss_coef = 0.0;
        batch.advantages.iter_mut().for_each(|a| *a = 1.0);
        let mut grads = Gradients::zeros(&policy);
        let before = loss_and_gradients(&policy, &config, &batch, &mut LossScratch::default(), &mut grads, 1);
        for (p, g) in policy.actor.params_mut().iter_mut().zip(&grads.actor) {
            *p -= 1e-3 * g;
        }
        for (p, g) in policy.log_std.iter_mut().zip(&grads.log_std) {
            *p -= 1e-3 * g;
        }
        let after = loss_and_gradients(&policy, &config, &batch, &mut LossScratch::default(), &mut grads, 1);
        assert!(after.surrogate < before.surrogate, "{} -> {}", before.surrogate, after.surrogate);
    }
}
