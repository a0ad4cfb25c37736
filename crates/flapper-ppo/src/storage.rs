//! Rollout storage: what every environment saw and did over one iteration's `steps` steps, and the
//! returns and advantages computed from it (generalized advantage estimation, Schulman et al. 2016).
//! Arrays are step-major: index = step * envs + env.

/// One step of every environment as the learner collected it (rsl_rl's `Transition`): filled by
/// `Ppo::act` (observations, actions, log-probabilities, means, values) and `Ppo::process_step`
/// (rewards, dones), then stored with [`RolloutStorage::add_transition`]. Row-major per environment.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Transition {
    /// Normalized observations the actions were taken at.
    pub observations: Vec<f32>,
    pub actions: Vec<f32>,
    pub log_probs: Vec<f32>,
    pub means: Vec<f32>,
    pub values: Vec<f32>,
    pub rewards: Vec<f32>,
    pub dones: Vec<bool>,
    /// The weight of the smoothness term for each environment's action (empty: every weight 1).
    pub smoothness_weights: Vec<f32>,
}

/// Read by the update; written only through [`RolloutStorage::add_transition`].
#[derive(Debug, Clone)]
pub struct RolloutStorage {
    pub steps: usize,
    pub envs: usize,
    pub observation_size: usize,
    pub action_size: usize,
    /// Normalized observations the actions were taken at.
    pub observations: Vec<f32>,
    pub actions: Vec<f32>,
    /// log pi_old(a | s) at collection.
    pub log_probs: Vec<f32>,
    /// The actor's means at collection (for the KL of the adaptive schedule).
    pub means: Vec<f32>,
    /// V_old(s) at collection.
    pub values: Vec<f32>,
    /// Rewards, with gamma V(final observation) added where an episode was truncated.
    pub rewards: Vec<f32>,
    /// The episode ended (terminated or truncated) after this step.
    pub dones: Vec<bool>,
    /// The weight of the smoothness term for each sample (1 where the environment gives none).
    pub smoothness_weights: Vec<f32>,
    pub advantages: Vec<f32>,
    pub returns: Vec<f32>,
    filled: usize,
}

impl RolloutStorage {
    pub fn new(steps: usize, envs: usize, observation_size: usize, action_size: usize) -> Self {
        let n = steps * envs;
        Self {
            steps,
            envs,
            observation_size,
            action_size,
            observations: vec![0.0; n * observation_size],
            actions: vec![0.0; n * action_size],
            log_probs: vec![0.0; n],
            means: vec![0.0; n * action_size],
            values: vec![0.0; n],
            rewards: vec![0.0; n],
            dones: vec![false; n],
            smoothness_weights: vec![1.0; n],
            advantages: vec![0.0; n],
            returns: vec![0.0; n],
            filled: 0,
        }
    }

    pub fn len(&self) -> usize {
        self.steps * self.envs
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    pub fn is_full(&self) -> bool {
        self.filled == self.steps
    }

    /// The step being filled.
    pub fn step(&self) -> usize {
        self.filled
    }

    /// Stores one step of every environment in the next free rows.
    pub fn add_transition(&mut self, t: &Transition) {
        assert!(self.filled < self.steps, "rollout storage is full");
        let rows = self.rows(self.filled);
        let (o, a) = (self.observation_size, self.action_size);
        self.observations[rows.start * o..rows.end * o].copy_from_slice(&t.observations);
        self.actions[rows.start * a..rows.end * a].copy_from_slice(&t.actions);
        self.means[rows.start * a..rows.end * a].copy_from_slice(&t.means);
        self.log_probs[rows.clone()].copy_from_slice(&t.log_probs);
        self.values[rows.clone()].copy_from_slice(&t.values);
        self.rewards[rows.clone()].copy_from_slice(&t.rewards);
        if t.smoothness_weights.is_empty() {
            self.smoothness_weights[rows.clone()].fill(1.0);
        } else {
            self.smoothness_weights[rows.clone()].copy_from_slice(&t.smoothness_weights);
        }
        self.dones[rows].copy_from_slice(&t.dones);
        self.filled += 1;
    }

    pub fn clear(&mut self) {
        self.filled = 0;
    }

    /// Index range of step `step` in the per-sample arrays.
    pub fn rows(&self, step: usize) -> std::ops::Range<usize> {
        step * self.envs..(step + 1) * self.envs
    }

    /// The rows of sample `i`'s step before and step after in the same environment, where they belong
    /// to the same episode and this rollout (a done step ends its episode).
    pub fn neighbours_in_episode(&self, i: usize) -> [Option<usize>; 2] {
        let (step, envs) = (i / self.envs, self.envs);
        let before = (step > 0 && !self.dones[i - envs]).then(|| i - envs);
        let after = (step + 1 < self.steps && !self.dones[i]).then_some(i + envs);
        [before, after]
    }

    /// GAE(gamma, lambda): advantages and returns (= advantages + values), given the values of the
    /// observations after the last step. A done step does not look past itself.
    pub fn compute_returns(&mut self, last_values: &[f32], gamma: f32, lambda: f32) {
        assert!(self.is_full(), "returns need a full rollout");
        assert_eq!(last_values.len(), self.envs);
        let envs = self.envs;
        let mut running = vec![0.0f32; envs];
        for step in (0..self.steps).rev() {
            for env in 0..envs {
                let i = step * envs + env;
                let next_value = if step + 1 == self.steps { last_values[env] } else { self.values[i + envs] };
                let not_done = if self.dones[i] { 0.0 } else { 1.0 };
                let delta = self.rewards[i] + gamma * next_value * not_done - self.values[i];
                running[env] = delta + gamma * lambda * not_done * running[env];
                self.advantages[i] = running[env];
                self.returns[i] = running[env] + self.values[i];
            }
        }
    }

    /// Shifts and scales the advantages to zero mean and unit standard deviation.
    pub fn normalize_advantages(&mut self) {
        let n = self.advantages.len() as f64;
        let mean = self.advantages.iter().map(|&a| a as f64).sum::<f64>() / n;
        let var = self.advantages.iter().map(|&a| (a as f64 - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        let scale = 1.0 / (var.sqrt() + 1e-8);
        for a in &mut self.advantages {
            *a = ((*a as f64 - mean) * scale) as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn filled(rewards: &[f32], values: &[f32], dones: &[bool]) -> RolloutStorage {
        let mut s = RolloutStorage::new(rewards.len(), 1, 1, 1);
        for k in 0..rewards.len() {
            s.add_transition(&Transition {
                observations: vec![k as f32],
                actions: vec![0.5],
                log_probs: vec![-1.0],
                means: vec![0.25],
                values: vec![values[k]],
                rewards: vec![rewards[k]],
                dones: vec![dones[k]],
                smoothness_weights: Vec::new(),
            });
        }
        assert!(s.is_full());
        s
    }

    #[test]
    fn a_transition_lands_in_its_step_rows() {
        let mut s = RolloutStorage::new(2, 2, 3, 1);
        let step = |v: f32| Transition {
            observations: vec![v; 6],
            actions: vec![v; 2],
            log_probs: vec![v; 2],
            means: vec![v; 2],
            values: vec![v; 2],
            rewards: vec![v; 2],
            dones: vec![v > 1.5; 2],
            smoothness_weights: if v > 1.5 { vec![0.25, 0.0] } else { Vec::new() },
        };
        s.add_transition(&step(1.0));
        s.add_transition(&step(2.0));
        assert_eq!(s.smoothness_weights, [1.0, 1.0, 0.25, 0.0], "none given: 1");
        assert_eq!(s.observations, [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 2.0, 2.0, 2.0]);
        assert_eq!(s.rewards, [1.0, 1.0, 2.0, 2.0]);
        assert_eq!(s.dones, [false, false, true, true]);
        assert!(s.is_full());
    }

    #[test]
    fn neighbours_stay_in_their_environment_episode_and_rollout() {
        // Two environments, three steps; environment 1's episode ends after step 0.
        let mut s = RolloutStorage::new(3, 2, 1, 1);
        for step in 0..3 {
            s.add_transition(&Transition {
                observations: vec![0.0; 2],
                actions: vec![0.0; 2],
                log_probs: vec![0.0; 2],
                means: vec![0.0; 2],
                values: vec![0.0; 2],
                rewards: vec![0.0; 2],
                dones: vec![false, step == 0],
                smoothness_weights: Vec::new(),
            });
        }
        // Rows: step * 2 + env.
        assert_eq!(s.neighbours_in_episode(0), [None, Some(2)]);
        assert_eq!(s.neighbours_in_episode(2), [Some(0), Some(4)]);
        assert_eq!(s.neighbours_in_episode(4), [Some(2), None]);
        assert_eq!(s.neighbours_in_episode(1), [None, None], "its episode ended at step 0");
        assert_eq!(s.neighbours_in_episode(3), [None, Some(5)], "a new episode starts at step 1");
    }

    #[test]
    fn lambda_one_gives_discounted_returns_and_done_cuts_the_sum() {
        let mut s = filled(&[1.0, 2.0, 3.0], &[0.5, 0.1, -0.2], &[false, false, false]);
        s.compute_returns(&[10.0], 0.9, 1.0);
        let expected0 = 1.0 + 0.9 * 2.0 + 0.81 * 3.0 + 0.729 * 10.0;
        assert!((s.returns[0] - expected0).abs() < 1e-5, "{}", s.returns[0]);
        assert!((s.advantages[0] - (expected0 - 0.5)).abs() < 1e-5);

        let mut cut = filled(&[1.0, 2.0, 3.0], &[0.5, 0.1, -0.2], &[false, true, false]);
        cut.compute_returns(&[10.0], 0.9, 1.0);
        assert!((cut.returns[0] - (1.0 + 0.9 * 2.0)).abs() < 1e-5, "nothing after a done step counts");
        assert!((cut.returns[2] - (3.0 + 0.9 * 10.0)).abs() < 1e-5);
    }

    #[test]
    fn lambda_zero_gives_one_step_temporal_differences() {
        let mut s = filled(&[1.0, 2.0], &[0.5, 0.25], &[false, false]);
        s.compute_returns(&[4.0], 0.5, 0.0);
        assert!((s.advantages[0] - (1.0 + 0.5 * 0.25 - 0.5)).abs() < 1e-6);
        assert!((s.advantages[1] - (2.0 + 0.5 * 4.0 - 0.25)).abs() < 1e-6);
    }

    #[test]
    fn normalized_advantages_have_zero_mean_and_unit_std() {
        let mut s = filled(&[1.0, -2.0, 5.0, 0.5], &[0.0; 4], &[false; 4]);
        s.compute_returns(&[0.0], 0.9, 0.9);
        s.normalize_advantages();
        let mean: f32 = s.advantages.iter().sum::<f32>() / 4.0;
        let var: f32 = s.advantages.iter().map(|a| (a - mean).powi(2)).sum::<f32>() / 3.0;
        assert!(mean.abs() < 1e-6 && (var - 1.0).abs() < 1e-4);
    }
}
