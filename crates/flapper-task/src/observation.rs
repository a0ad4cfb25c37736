//! Observations (paper III-C). Per 20 ms frame, 18 numbers:
//!
//! | index | content |
//! |---|---|
//! | 0-3 | orientation quaternion w, x, y, z (body to world) |
//! | 4-6 | body-frame angular rates p, q, r (rad/s) |
//! | 7-11 | joint positions q1..q5 (rad) |
//! | 12 | pitot airspeed: body-x velocity relative to the wind (m/s) |
//! | 13-17 | previous action (5 numbers in [-1, 1]) |
//!
//! The policy sees the last `history_frames` frames, oldest first (25 frames, 450 numbers), then the
//! next `lookahead_steps` reference points (30 points, 90 numbers), each as the offset from the robot
//! to the point in the robot's body frame (x forward, y left, z up). 540 in all with the paper's
//! numbers. With `[observation] clock_hz` above 0 (not the paper's), two more close it: the sine and
//! cosine of a clock's phase, 2 pi f dt times the reference's step. [`ObservationLayout::names`] names
//! every index.

use std::collections::VecDeque;

use flapper_sim::{ActuatedJoint, N_ACTUATED_JOINTS, Quat, Simulator, Vec3, quat_to_wxyz};

use crate::action::ACTION_SIZE;
use crate::reference::Reference;

/// Numbers per history frame.
pub const FRAME_SIZE: usize = 4 + 3 + N_ACTUATED_JOINTS + 1 + ACTION_SIZE;

/// One frame of sensor readings and the previous action.
pub type Frame = [f32; FRAME_SIZE];

/// Sizes of the observation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ObservationLayout {
    pub history_frames: usize,
    pub lookahead_steps: usize,
    /// Whether the clock's sine and cosine close the observation.
    pub clock: bool,
}

/// Numbers the clock adds at the end of the observation.
pub const CLOCK_SIZE: usize = 2;

impl ObservationLayout {
    /// The layout a task config asks for.
    pub fn of(config: &crate::config::ObservationConfig) -> Self {
        Self {
            history_frames: config.history_frames,
            lookahead_steps: config.lookahead_steps,
            clock: config.clock_hz > 0.0,
        }
    }

    /// The paper's layout: 25 frames of history, 30 points ahead, no clock.
    pub fn paper() -> Self {
        Self::of(&crate::config::ObservationConfig::default())
    }

    pub fn size(&self) -> usize {
        self.lookahead_start() + 3 * self.lookahead_steps + self.clock_size()
    }

    /// Numbers at the end that a policy trained without them can be given with zero weights
    /// (the clock's; 0 without it).
    pub fn clock_size(&self) -> usize {
        if self.clock { CLOCK_SIZE } else { 0 }
    }

    /// Index of the first lookahead number.
    pub fn lookahead_start(&self) -> usize {
        self.history_frames * FRAME_SIZE
    }

    /// A name for every index, e.g. `t-24.quat_w`, `t-0.action.tail_pitch`, `ahead+01.x_body_m`.
    pub fn names(&self) -> Vec<String> {
        let mut frame_fields: Vec<String> =
            ["quat_w", "quat_x", "quat_y", "quat_z", "p_radps", "q_radps", "r_radps"].map(String::from).to_vec();
        frame_fields.extend(ActuatedJoint::ALL.map(|j| format!("joint.{}_rad", j.name())));
        frame_fields.push("airspeed_mps".into());
        frame_fields.extend(ActuatedJoint::ALL.map(|j| format!("action.{}", j.name())));
        let mut names = Vec::with_capacity(self.size());
        for age in (0..self.history_frames).rev() {
            names.extend(frame_fields.iter().map(|f| format!("t-{age}.{f}")));
        }
        for ahead in 1..=self.lookahead_steps {
            names.extend(["x_body_m", "y_body_m", "z_body_m"].map(|axis| format!("ahead+{ahead:02}.{axis}")));
        }
        if self.clock {
            names.extend(["clock.sin", "clock.cos"].map(String::from));
        }
        names
    }
}

/// The frame of the current state.
pub fn read_frame(sim: &Simulator, previous_action: &[f32; ACTION_SIZE]) -> Frame {
    let mut frame = [0.0f32; FRAME_SIZE];
    let q = quat_to_wxyz(sim.orientation());
    let rates = sim.body_rates().to_array();
    let joints = sim.joint_positions();
    let values = q.iter().chain(&rates).chain(&joints).copied().chain([sim.pitot_airspeed_mps()]);
    for (slot, value) in frame.iter_mut().zip(values) {
        *slot = value as f32;
    }
    frame[FRAME_SIZE - ACTION_SIZE..].copy_from_slice(previous_action);
    frame
}

/// Keeps the frame history and writes observations.
#[derive(Debug, Clone)]
pub struct ObservationBuilder {
    layout: ObservationLayout,
    history: VecDeque<Frame>,
    /// The clock's phase advance per reference step (rad; 0 without a clock).
    clock_radians_per_step: f64,
}

impl ObservationBuilder {
    /// A builder for `layout`, whose clock (if it has one) runs at `clock_hz` over reference steps of `step_s`.
    pub fn new(layout: ObservationLayout, clock_hz: f64, step_s: f64) -> Self {
        let clock_radians_per_step = if layout.clock { std::f64::consts::TAU * clock_hz * step_s } else { 0.0 };
        Self { layout, history: VecDeque::with_capacity(layout.history_frames), clock_radians_per_step }
    }

    pub fn layout(&self) -> ObservationLayout {
        self.layout
    }

    /// Starts an episode: the whole history is the first frame.
    pub fn reset(&mut self, frame: Frame) {
        self.history.clear();
        self.history.extend(std::iter::repeat_n(frame, self.layout.history_frames));
    }

    /// The frames held, oldest first.
    pub fn history(&self) -> Vec<Frame> {
        self.history.iter().copied().collect()
    }

    /// Replaces the history with `frames` (oldest first); false if their number does not fit the layout.
    pub fn restore_history(&mut self, frames: &[Frame]) -> bool {
        if frames.len() != self.layout.history_frames {
            return false;
        }
        self.history.clear();
        self.history.extend(frames.iter().copied());
        true
    }

    pub fn push(&mut self, frame: Frame) {
        if self.history.len() == self.layout.history_frames {
            self.history.pop_front();
        }
        self.history.push_back(frame);
    }

    /// Writes the observation for control step `step` of `reference` into `out` (length `size()`).
    pub fn write(&self, reference: &Reference, step: usize, position: Vec3, orientation: Quat, out: &mut [f32]) {
        debug_assert_eq!(out.len(), self.layout.size());
        for (chunk, frame) in out.chunks_exact_mut(FRAME_SIZE).zip(&self.history) {
            chunk.copy_from_slice(frame);
        }
        let (lookahead, clock) = out[self.layout.lookahead_start()..].split_at_mut(3 * self.layout.lookahead_steps);
        let to_body = orientation.inverse();
        for (i, slot) in lookahead.chunks_exact_mut(3).enumerate() {
            let offset = to_body * (reference.target(step + 1 + i) - position);
            slot.copy_from_slice(&[offset.x as f32, offset.y as f32, offset.z as f32]);
        }
        if self.layout.clock {
            // Taken modulo one turn in f64 before the sine, so that it stays accurate however long the path.
            let phase = (step as f64 * self.clock_radians_per_step).rem_euclid(std::f64::consts::TAU);
            clock.copy_from_slice(&[phase.sin() as f32, phase.cos() as f32]);
        }
    }
}
