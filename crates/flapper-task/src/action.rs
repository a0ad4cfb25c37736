//! Actions (paper III-C): five numbers in [-1, 1]. Out-of-range values are clipped; a non-finite value
//! counts as 0. What they ask for depends on the task's `control.action_mode`:
//!
//! - `joint_targets` (the paper, the default): one target per actuated joint in the order q1..q5,
//!   centred on the nominal pose (wings and tail flat at 0) and scaled to each joint's limit.
//! - `flap_oscillator`: the wings follow a flapping oscillator whose shape the policy sets each step,
//!   so that holding the wings still is one output rather than a limit cycle to unlearn:
//!
//!   | action | asks for |
//!   |---|---|
//!   | a1 | flap amplitude: `max(a1, 0)` times `flap_amplitude_max` times the flap limit; any a1 <= 0 holds the wings (glide) |
//!   | a2 | flap frequency, from `flap_frequency_hz[0]` at -1 to `[1]` at +1; or, with `oscillator_a2 = "wing_pitch"`, a common pitch of both wings (a joint target added to each wing's pitch; the frequency then fixed at the middle of `flap_frequency_hz`) |
//!   | a3 | flap bias (dihedral) of both wings: the stroke's centre, as a joint target |
//!   | a4 | roll: differential wing pitch, +a4 on the left wing and -a4 on the right, and, with `differential_flap` k, flap amplitudes A (1 - k a4) left and A (1 + k a4) right: both take lift from the left wing |
//!   | a5 | tail pitch, as a joint target |
//!
//!   Both wings flap in phase about their bias, `bias + A sin(phase)`, clipped to the joint limit (so an
//!   amplitude above the limit flattens the stroke towards a square wave, as a bang-bang joint-target
//!   policy flaps); each wing's pitch swings with the flap, [`PITCH_SWING_PER_FLAP`] times its amplitude
//!   and leading it by a quarter cycle (the scripted gait's shape), about the roll differential. A held
//!   wing (a1 <= 0) sits at its bias with its pitch at the differential. The phase advances by `2 pi f`
//!   times the control period at every step. With `flap_shape_filter_hz` above 0, the amplitude, the
//!   bias and the roll follow a1, a3 and a4 through a first-order low-pass filter of that cutoff, so that
//!   the stroke's shape cannot be dithered faster than the wings flap (an unfiltered bias was jittered at
//!   15.7 Hz and, with amplitude and bias filtered, the roll's wing pitch at 22.8 Hz; docs/experiments.md).
//!
//!   The third action is the flap bias, not a common wing pitch: the joint-target controller flies its
//!   loops by moving the stroke's centre (flap between +6 and +57 deg over the top of the loop, -59 to
//!   -11 deg on the way down) and a first oscillator with a common wing pitch instead learned no loop in
//!   1100 stage-3 iterations (docs/experiments.md, "Oscillator actions").

use flapper_sim::{ActuatedJoint, N_ACTUATED_JOINTS, Simulator};
use serde::{Deserialize, Serialize};

use crate::config::{ActionMode, ControlConfig, OscillatorA2};

/// Action size (n_j = 5).
pub const ACTION_SIZE: usize = N_ACTUATED_JOINTS;

/// Wing-pitch swing per unit of flap amplitude in `flap_oscillator` mode (the scripted gait's 10 deg
/// for 20 deg).
pub const PITCH_SWING_PER_FLAP: f64 = 0.5;

/// What the flapping oscillator carries from one step to the next (all 0 in `joint_targets` mode).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct OscillatorState {
    pub phase_rad: f64,
    /// a1, a3 and a4 as filtered and rate-limited (or as last given, without either).
    pub amplitude: f64,
    pub bias: f64,
    #[serde(default)]
    pub roll: f64,
    /// a2 as filtered and rate-limited, with `oscillator_a2 = "wing_pitch"` (0 otherwise).
    #[serde(default)]
    pub wing_pitch: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActionMap {
    /// Target (rad) reached by an action of +1 for each joint.
    half_range_rad: [f64; N_ACTUATED_JOINTS],
    mode: ActionMode,
    a2: OscillatorA2,
    frequency_hz: [f64; 2],
    differential_flap: f64,
    amplitude_max: f64,
    /// Share of the way to a new amplitude, bias, roll or wing pitch covered per step (1 without the
    /// shape filter).
    shape_step_fraction: f64,
    /// Largest change of amplitude, bias, roll or wing pitch per step (infinite without the rate limit).
    shape_max_step: f64,
    control_period_s: f64,
}

/// Clips to [-1, 1]; a missing or non-finite number is 0.
fn clipped(action: &[f32], i: usize) -> f64 {
    let a = action.get(i).copied().unwrap_or(0.0) as f64;
    if a.is_finite() { a.clamp(-1.0, 1.0) } else { 0.0 }
}

impl ActionMap {
    /// Scales to `action_scale` times each joint's limit (symmetric ranges: the nominal pose is 0); the
    /// oscillator's settings come from `control` too, its phase steps by `control_period_s`.
    pub fn new(sim: &Simulator, control: &ControlConfig, control_period_s: f64) -> Self {
        let ranges = sim.joint_ranges();
        Self {
            half_range_rad: ranges.map(|[low, high]| control.action_scale * high.min(-low)),
            mode: control.action_mode,
            a2: control.oscillator_a2,
            frequency_hz: control.flap_frequency_hz,
            differential_flap: control.differential_flap,
            amplitude_max: control.flap_amplitude_max,
            shape_step_fraction: if control.flap_shape_filter_hz > 0.0 {
                1.0 - (-std::f64::consts::TAU * control.flap_shape_filter_hz * control_period_s).exp()
            } else {
                1.0
            },
            shape_max_step: if control.flap_shape_rate_limit > 0.0 {
                control.flap_shape_rate_limit * control_period_s
            } else {
                f64::INFINITY
            },
            control_period_s,
        }
    }

    /// One step of a shape channel (amplitude, bias, roll or wing pitch) from `current` towards `asked`: the
    /// shape filter's share of the way, at most the rate limit's step.
    fn shape_step(&self, current: f64, asked: f64) -> f64 {
        current + (self.shape_step_fraction * (asked - current)).clamp(-self.shape_max_step, self.shape_max_step)
    }

    /// Adds passive feathering to `targets`: each wing's pitch target plus `feathering_s` times its own
    /// flap rate in `joint_velocities_radps`, clipped to the pitch limit (`control.passive_feathering_s`).
    pub fn feather(
        &self,
        targets: &mut [f64; N_ACTUATED_JOINTS],
        joint_velocities_radps: &[f64; N_ACTUATED_JOINTS],
        feathering_s: f64,
    ) {
        for (flap, pitch) in
            [(ActuatedJoint::FlapLeft, ActuatedJoint::PitchLeft), (ActuatedJoint::FlapRight, ActuatedJoint::PitchRight)]
        {
            let limit = self.half_range_rad[pitch.index()];
            let twisted = targets[pitch.index()] + feathering_s * joint_velocities_radps[flap.index()];
            targets[pitch.index()] = twisted.clamp(-limit, limit);
        }
    }

    /// Joint targets (rad) for an action. `oscillator` is the oscillator's state, which this advances
    /// (`flap_oscillator`; untouched in `joint_targets` mode).
    pub fn to_targets(&self, action: &[f32], oscillator: &mut OscillatorState) -> [f64; N_ACTUATED_JOINTS] {
        let a: [f64; N_ACTUATED_JOINTS] = std::array::from_fn(|i| clipped(action, i));
        match self.mode {
            ActionMode::JointTargets => std::array::from_fn(|i| a[i] * self.half_range_rad[i]),
            ActionMode::FlapOscillator => {
                let [asked_amplitude, second, asked_bias, asked_roll, tail] = a;
                oscillator.amplitude = self.shape_step(oscillator.amplitude, asked_amplitude);
                oscillator.bias = self.shape_step(oscillator.bias, asked_bias);
                oscillator.roll = self.shape_step(oscillator.roll, asked_roll);
                // The frequency's position in its range (0 = the middle), or the common wing pitch.
                let frequency = match self.a2 {
                    OscillatorA2::Frequency => second,
                    OscillatorA2::WingPitch => {
                        oscillator.wing_pitch = self.shape_step(oscillator.wing_pitch, second);
                        0.0
                    }
                };
                let (amplitude, bias, differential) = (oscillator.amplitude, oscillator.bias, oscillator.roll);
                let common_pitch = oscillator.wing_pitch;
                let [low_hz, high_hz] = self.frequency_hz;
                let frequency_hz = low_hz + 0.5 * (frequency + 1.0) * (high_hz - low_hz);
                let phase = (oscillator.phase_rad + std::f64::consts::TAU * frequency_hz * self.control_period_s)
                    % std::f64::consts::TAU;
                oscillator.phase_rad = phase;
                let flap_half_range = self.half_range_rad[ActuatedJoint::FlapLeft.index()];
                let pitch_half_range = self.half_range_rad[ActuatedJoint::PitchLeft.index()];
                let (sin, cos) = phase.sin_cos();
                // Flap and pitch targets of one wing, side +1 left, -1 right. A positive roll action pitches
                // the left wing's leading edge down and the right one's up (less lift left, more right),
                // and flaps the left wing less.
                let wing = |side: f64| {
                    let roll = 1.0 - side * self.differential_flap * differential;
                    let flap_amplitude = amplitude.max(0.0) * self.amplitude_max * roll * flap_half_range;
                    let flap = (bias * flap_half_range + flap_amplitude * sin).clamp(-flap_half_range, flap_half_range);
                    let swing = PITCH_SWING_PER_FLAP * flap_amplitude * cos;
                    let pitch = ((side * differential + common_pitch) * pitch_half_range + swing)
                        .clamp(-pitch_half_range, pitch_half_range);
                    (flap, pitch)
                };
                let ((flap_left, pitch_left), (flap_right, pitch_right)) = (wing(1.0), wing(-1.0));
                let tail = tail * self.half_range_rad[ActuatedJoint::TailPitch.index()];
                [flap_left, pitch_left, flap_right, pitch_right, tail]
            }
        }
    }

    /// The action recorded as "previous action" after `action` asked for `targets_rad`: the joint
    /// targets as actions (`joint_targets`), or the clipped action itself (`flap_oscillator`).
    pub fn applied(&self, action: &[f32], targets_rad: &[f64; N_ACTUATED_JOINTS]) -> [f32; N_ACTUATED_JOINTS] {
        match self.mode {
            ActionMode::JointTargets => self.to_action(targets_rad),
            ActionMode::FlapOscillator => std::array::from_fn(|i| clipped(action, i) as f32),
        }
    }

    /// The "previous action" of a robot at rest in `joint_positions_rad` at an episode's start: the
    /// joint-target action that holds them (`joint_targets`), or held wings with their flap, their
    /// pitch difference and the tail where they are (`flap_oscillator`).
    pub fn at_rest(&self, joint_positions_rad: &[f64; N_ACTUATED_JOINTS]) -> [f32; N_ACTUATED_JOINTS] {
        let joint_action = self.to_action(joint_positions_rad);
        match self.mode {
            ActionMode::JointTargets => joint_action,
            ActionMode::FlapOscillator => {
                let at = |joint: ActuatedJoint| joint_action[joint.index()];
                let bias = 0.5 * (at(ActuatedJoint::FlapLeft) + at(ActuatedJoint::FlapRight));
                let differential = 0.5 * (at(ActuatedJoint::PitchLeft) - at(ActuatedJoint::PitchRight));
                let second = match self.a2 {
                    OscillatorA2::Frequency => 0.0,
                    OscillatorA2::WingPitch => 0.5 * (at(ActuatedJoint::PitchLeft) + at(ActuatedJoint::PitchRight)),
                };
                [0.0, second, bias, differential, at(ActuatedJoint::TailPitch)]
            }
        }
    }

    /// The oscillator at an episode's start, after [`ActionMap::at_rest`] gave `previous_action`: no
    /// phase, wings held at their bias and pitch difference.
    pub fn oscillator_at_rest(&self, previous_action: &[f32; N_ACTUATED_JOINTS]) -> OscillatorState {
        match self.mode {
            ActionMode::JointTargets => OscillatorState::default(),
            ActionMode::FlapOscillator => {
                let [_, second, bias, roll, _] = previous_action.map(f64::from);
                let wing_pitch = if self.a2 == OscillatorA2::WingPitch { second } else { 0.0 };
                OscillatorState { bias, roll, wing_pitch, ..Default::default() }
            }
        }
    }

    /// The joint-target action that asks for `targets_rad` (inverse of `to_targets` in `joint_targets`
    /// mode, inside the range).
    pub fn to_action(&self, targets_rad: &[f64; N_ACTUATED_JOINTS]) -> [f32; N_ACTUATED_JOINTS] {
        std::array::from_fn(|i| (targets_rad[i] / self.half_range_rad[i]).clamp(-1.0, 1.0) as f32)
    }

    pub fn half_range_rad(&self) -> [f64; N_ACTUATED_JOINTS] {
        self.half_range_rad
    }
}
