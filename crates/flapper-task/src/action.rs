//! Actions (paper III-C): five numbers in [-1, 1], one per actuated joint in the order q1..q5,
//! centred on the nominal pose (wings and tail flat at 0) and scaled to each joint's limit.
//! Out-of-range values are clipped; a non-finite value counts as 0.

use flapper_sim::{N_ACTUATED_JOINTS, Simulator};

/// Action size (n_j = 5).
pub const ACTION_SIZE: usize = N_ACTUATED_JOINTS;

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActionMap {
    /// Target (rad) reached by an action of +1 for each joint.
    half_range_rad: [f64; N_ACTUATED_JOINTS],
}

impl ActionMap {
    /// Scales to `action_scale` times each joint's limit (symmetric ranges: the nominal pose is 0).
    pub fn new(sim: &Simulator, action_scale: f64) -> Self {
        let ranges = sim.joint_ranges();
        Self { half_range_rad: ranges.map(|[low, high]| action_scale * high.min(-low)) }
    }

    /// Joint targets (rad) for an action.
    pub fn to_targets(&self, action: &[f32]) -> [f64; N_ACTUATED_JOINTS] {
        std::array::from_fn(|i| {
            let a = action.get(i).copied().unwrap_or(0.0) as f64;
            let a = if a.is_finite() { a.clamp(-1.0, 1.0) } else { 0.0 };
            a * self.half_range_rad[i]
        })
    }

    /// The action that asks for `targets_rad` (inverse of `to_targets` inside the range).
    pub fn to_action(&self, targets_rad: &[f64; N_ACTUATED_JOINTS]) -> [f32; N_ACTUATED_JOINTS] {
        std::array::from_fn(|i| (targets_rad[i] / self.half_range_rad[i]).clamp(-1.0, 1.0) as f32)
    }

    pub fn half_range_rad(&self) -> [f64; N_ACTUATED_JOINTS] {
        self.half_range_rad
    }
}
