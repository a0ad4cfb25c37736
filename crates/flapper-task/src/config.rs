//! Every number of the task in one typed config: the paper's values are the defaults, written once
//! here; a TOML file overrides any of them. Curriculum stages (paper III-A, III-F) are presets of this
//! config, so moving between stages never changes the observation or action layout.

use std::path::Path;

use serde::{Deserialize, Serialize};

/// Any problem with a task configuration, naming the file, key or value.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("cannot read config '{path}': {source}")]
    Read { path: String, source: std::io::Error },
    #[error("config '{path}': {message}")]
    Parse { path: String, message: String },
    #[error("config value {key} = {value}: {why}")]
    Invalid { key: &'static str, value: String, why: &'static str },
    #[error("config value {key} = {value}: must be a finite number in [{low}, {high}]")]
    OutOfRange { key: &'static str, value: String, low: f64, high: f64 },
    #[error("config value {key} = {value}: must be at most {max} (larger would not fit in memory or time)")]
    TooLarge { key: &'static str, value: String, max: String },
    #[error("unknown curriculum stage {0} (stages are 1 to 4)")]
    UnknownStage(i64),
}

impl ConfigError {
    /// The message without the file a parse error names, for a caller whose own message names it.
    pub fn detail(&self) -> String {
        match self {
            ConfigError::Parse { message, .. } => message.clone(),
            other => other.to_string(),
        }
    }
}

/// A closed interval `[low, high]` to sample from uniformly.
pub type Interval = [f64; 2];

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TaskConfig {
    /// Curriculum stage this config was built from (1-4); informational once loaded.
    pub stage: u8,
    pub control: ControlConfig,
    pub observation: ObservationConfig,
    pub reward: RewardConfig,
    pub episode: EpisodeConfig,
    pub reference: ReferenceConfig,
    pub initial_state: InitialStateConfig,
    pub randomization: RandomizationConfig,
}

/// Paper III-A: policy at 50 Hz, simulation at 250 Hz, 7 Hz filter on the targets.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ControlConfig {
    /// Simulation steps (4 ms each) per policy step.
    pub substeps: usize,
    pub filter_cutoff_hz: f64,
    /// Fraction of each joint's limit that an action of +-1 reaches.
    pub action_scale: f64,
    /// What the five action numbers mean: joint targets (the paper) or a flapping oscillator's
    /// amplitude, frequency, bias, roll and tail ([`ActionMode`]).
    pub action_mode: ActionMode,
    /// The oscillator's frequency range (Hz), from an action of -1 to +1 (`flap_oscillator` only).
    pub flap_frequency_hz: [f64; 2],
    /// What the oscillator's second action asks for: the frequency (default) or a common wing pitch,
    /// the frequency then fixed at the middle of `flap_frequency_hz` (`flap_oscillator` only).
    pub oscillator_a2: OscillatorA2,
    /// Flap amplitude difference per unit of the roll action (`flap_oscillator` only): left
    /// A (1 - k a4), right A (1 + k a4); 0 rolls by wing pitch alone.
    pub differential_flap: f64,
    /// The flap amplitude of a1 = +1 as a multiple of the flap limit (`flap_oscillator` only); the
    /// targets are clipped to the limit, so above 1 the stroke flattens towards a square wave.
    pub flap_amplitude_max: f64,
    /// Cutoff (Hz) of a first-order filter on the oscillator's amplitude, bias and roll (and wing pitch)
    /// (`flap_oscillator` only); 0 applies them as given.
    pub flap_shape_filter_hz: f64,
    /// Largest rate of change (action units per second) of the oscillator's amplitude, bias and roll (and
    /// wing pitch) (`flap_oscillator` only); 0 leaves them free. Unlike the filter it delays no slow change: it
    /// bounds how fast the stroke's shape moves, so a dither between steps shrinks to this rate.
    pub flap_shape_rate_limit: f64,
    /// Passive feathering (s; not the paper's, 0 leaves it out of the control and of a written config):
    /// each wing's pitch target gets this times its own flap joint's rate (rad/s), as a wing that twists
    /// under its stroke would, so that the pitch leads the flap by a quarter period (the scripted gait's
    /// shape) whatever the policy asks (docs/experiments.md, "The learned stroke feathers backwards").
    /// A policy trained with it needs it on the robot: `flapper export-policy` refuses one.
    #[serde(skip_serializing_if = "is_zero")]
    pub passive_feathering_s: f64,
}

/// An experimental key that is off at 0, left out of a written config there.
fn is_zero(value: &f64) -> bool {
    *value == 0.0
}

/// What an action asks for.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ActionMode {
    /// One joint target per joint (paper III-C).
    #[default]
    JointTargets,
    /// Flap amplitude, flap frequency, flap bias, roll (differential wing pitch and amplitude), tail pitch.
    FlapOscillator,
}

/// What the oscillator's second action asks for (`control.oscillator_a2`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OscillatorA2 {
    /// The flap frequency, over `flap_frequency_hz`.
    #[default]
    Frequency,
    /// A common pitch of both wings (angle of attack: lift and drag without a flap), the frequency fixed
    /// at the middle of `flap_frequency_hz`.
    WingPitch,
}

/// Paper III-C: 25 frames of history (0.5 s) and 30 reference points ahead (0.6 s).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ObservationConfig {
    pub history_frames: usize,
    pub lookahead_steps: usize,
    /// Not the paper's: above 0, a clock of this frequency (Hz) appended to the observation as the sine
    /// and cosine of its phase, which advances with the reference's step, so that a stroke can follow
    /// a rhythm of its own instead of the closed loop's. 0 (the default) leaves it out, and out of a
    /// written config.
    #[serde(skip_serializing_if = "is_default_clock_hz")]
    pub clock_hz: f64,
}

fn is_default_clock_hz(value: &f64) -> bool {
    *value == ObservationConfig::default().clock_hz
}

/// Paper III-D: r = 0.5 r_pos + 0.1 r_rate + 0.2 r_level + 0.05 r_energy. The paper gives the weights;
/// the kernels are ours: each term is exp(-x^2 / scale^2) (energy: exp(-P / scale)), so it lies in (0, 1].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RewardConfig {
    pub position_weight: f64,
    pub body_rate_weight: f64,
    pub level_weight: f64,
    pub energy_weight: f64,
    /// Position error at which r_pos falls to 1/e.
    pub position_scale_m: f64,
    /// Norm of (p, q, r) at which r_rate falls to 1/e.
    pub body_rate_scale_radps: f64,
    /// sqrt(roll^2 + pitch^2) at which r_level falls to 1/e.
    pub level_scale_rad: f64,
    /// Mean absolute mechanical power at which r_energy falls to 1/e.
    pub energy_scale_w: f64,
    /// Weight of r_action_rate (not the paper's; 0 leaves it out).
    pub action_rate_weight: f64,
    /// Norm of the step-to-step change of the applied action at which r_action_rate falls to 1/e.
    pub action_rate_scale: f64,
    /// Weight of r_flap_rate (not the paper's; 0 leaves it out): the price on a flap faster than
    /// `flap_max_hz`, the frequency read online from the left flap joint's tops. The three flap keys
    /// are left out of a written config at their defaults, so configs written before them read and
    /// write the same.
    #[serde(skip_serializing_if = "is_default_flap_rate_weight")]
    pub flap_rate_weight: f64,
    /// The fastest flap (Hz) r_flap_rate leaves unpriced: the paper's 4-6 Hz, a little inside its top.
    #[serde(skip_serializing_if = "is_default_flap_max_hz")]
    pub flap_max_hz: f64,
    /// How far (Hz) above `flap_max_hz` r_flap_rate falls to 1/e.
    #[serde(skip_serializing_if = "is_default_flap_rate_scale_hz")]
    pub flap_rate_scale_hz: f64,
    /// The share of r_flap_rate's price paid where the reference sinks at a glide slope (the slopes of
    /// `smoothness_glide_gain`, in full from a sink rate of [`GLIDE_SINK_MPS`]): 1 prices a fast stroke
    /// there as everywhere, 0 leaves the glide slopes to the glide's own prices.
    #[serde(skip_serializing_if = "is_default_flap_rate_glide_share")]
    pub flap_rate_glide_share: f64,
    /// Weight of r_glide_hold (not the paper's; 0 leaves it out): pays a held wing where the reference
    /// sinks at a glide slope (the slopes of `smoothness_glide_gain`, in full from a sink rate of
    /// [`GLIDE_SINK_MPS`]), by how little the left flap swings over the last 0.4 s
    /// ([`crate::flap_rhythm::FlapSwing`]). Where the path does not glide it pays nothing. Both glide
    /// keys are left out of a written config at their defaults.
    #[serde(skip_serializing_if = "is_default_glide_hold_weight")]
    pub glide_hold_weight: f64,
    /// Weight of r_feathering (not the paper's; 0, the default, leaves it out of the reward and of a
    /// written config): pays a stroke whose wing pitch leads the flap by a quarter period, the scripted
    /// gait's feathering, by the correlation of the wings' common pitch with their common flap rate over
    /// the last 0.4 s ([`crate::flap_rhythm::StrokeFeathering`]), nothing on glide slopes (where the
    /// held wing is paid). At 5.3 m/s the scripted gait's family flies level on 14 W with the pitch
    /// leading by 90 deg and needs 23-25 W with it lagging by 75 deg, the trained controllers' phase
    /// (docs/experiments.md, "The learned stroke feathers backwards").
    #[serde(skip_serializing_if = "is_zero")]
    pub feathering_weight: f64,
    /// The flap's swing (deg, peak to peak over the last 0.4 s) at which r_glide_hold falls to 1/e of its
    /// top: by default the range under which `flapper modes` counts the wing as held.
    #[serde(skip_serializing_if = "is_default_glide_hold_scale_deg")]
    pub glide_hold_scale_deg: f64,
    /// Pays r_glide_hold only where the path runs straight: above 0, its glide share is weighed by
    /// exp(-(w / scale)^2), w the fastest turn of the reference over the observed lookahead (deg/s, as
    /// `smoothness_turn_scale_degps`), so that a sinking turn, which needs the stroke, is not paid for a
    /// held wing. 0 (the default, left out of a written config) pays every glide slope alike.
    #[serde(skip_serializing_if = "is_default_glide_hold_turn_scale_degps")]
    pub glide_hold_turn_scale_degps: f64,
    /// Not a reward term: where the learner's smoothness term (`ppo.smoothness_coef`) applies. Above 0,
    /// each step's weight of it is exp(-(w / scale)^2), w the fastest turn of the reference path over
    /// the observed lookahead (deg/s), so that a steady stroke is asked on straight and gently curving
    /// paths and manoeuvres may change it quickly; 0 weighs every step 1.
    pub smoothness_turn_scale_degps: f64,
    /// Weighs the smoothness term by the reference's speed too: 1 at or above this speed (m/s), falling
    /// linearly to 0 at [`SPEED_RAMP_MPS`] below it, so that slow flight, which needs a fast
    /// stroke and quick corrections, is not asked for a steady one; 0 weighs every speed 1.
    pub smoothness_min_speed_mps: f64,
    /// Weighs the smoothness term more where the reference path sinks at a slope the robot can glide
    /// (horizontal over sink speed at least [`GLIDE_MIN_RATIO`]): times 1 + this gain from a
    /// sink rate of [`GLIDE_SINK_MPS`] on, rising linearly from 1 on a level path, so that a
    /// glide slope, which the robot can fly with its wings held, asks for a held stroke; level flight,
    /// climbs and steeper dives (which need quick corrections) weigh 1. 0 weighs every slope 1.
    pub smoothness_glide_gain: f64,
    /// Lifts `smoothness_glide_gain` this long (s) before the reference dives steeper than a glide slope:
    /// a glide slope with a dive within this time ahead weighs the smoothness as level flight, so that the
    /// stroke is free to change while the path turns down into the dive. Measured, 0.6 s (the observed
    /// lookahead) did not keep seed 2's dive, which its glide stage loses with the x10 price as without
    /// this (docs/experiments.md, "The glide, then its pay, in one run; and the dive left free"). 0 (the
    /// default, left out of a written config) weighs every glide-slope step alike.
    #[serde(skip_serializing_if = "is_default_smoothness_glide_stop_before_dive_s")]
    pub smoothness_glide_stop_before_dive_s: f64,
    /// The share of the smoothness weight kept where the reference dives steeper than a glide slope
    /// (the dives of `energy_dive_share`), where the robot must flap to brake and hold the path: 1 weighs
    /// a dive as level flight, 0 asks no steady stroke there at all.
    pub smoothness_dive_share: f64,
    /// Prices the energy by the reference's speed: in full at or above this speed (m/s), less and less
    /// over the [`SPEED_RAMP_MPS`] below it and not at all further down, where r_energy reads
    /// its top (1) whatever the power. Slow flight needs power (the robot's power curve rises below
    /// its cruise speed), and a price on it teaches the policy to fly faster than asked; 0 prices the
    /// energy at every speed.
    pub energy_min_speed_mps: f64,
    /// Prices the energy more where the reference path sinks at a slope the robot can glide (the
    /// slopes of `smoothness_glide_gain`): the price times 1 + this gain from a sink rate of
    /// [`GLIDE_SINK_MPS`] on, so r_energy reads 1 - (1 + gain)(1 - e^(-P / scale)) there and falls
    /// below 0 for a flapping stroke: the paper's "gliding instead of flapping when possible", priced
    /// where it is possible. 0 prices every slope alike.
    pub energy_glide_gain: f64,
    /// The share of the energy's price paid where the reference dives steeper than a glide slope
    /// (sinking faster than horizontal speed / [`GLIDE_MIN_RATIO`]), where the robot must flap to brake
    /// and hold the path: 1 prices it as everywhere, 0 not at all (r_energy reads 1 there).
    pub energy_dive_share: f64,
    /// Lifts the energy's price in turns: above 0, each step's price is weighed by exp(-(w / scale)^2),
    /// w the fastest turn of the reference over the observed lookahead (deg/s, as
    /// `smoothness_turn_scale_degps`), so that a sharp turn, which needs a strong asymmetric stroke, is
    /// not taught to save power there (the held wing of a gliding stage 5 flew the sharp turn unbanked:
    /// docs/experiments.md, "The held wing paid inside the efficient stage"). 0 (the default, left out of
    /// a written config) prices every turn alike.
    #[serde(skip_serializing_if = "is_default_energy_turn_scale_degps")]
    pub energy_turn_scale_degps: f64,
    /// Weighs r_pos more where the reference dives steeper than a glide slope (the dives of
    /// `energy_dive_share`): r_pos times 1 + this gain there, times 1 on level paths, climbs and glide
    /// slopes. A stage that learns to hold its wings on glide slopes can hold them in a dive too, where the
    /// path needs the stroke to brake and steer (docs/experiments.md, "The glide's lost dive"); a dearer
    /// miss there asks it to tell the two apart. Measured, gain 2 did not: seed 2's glide stage lost the
    /// dive as without it ("A dearer dive, and what takes seed 2's dive"). 0 weighs every slope alike and
    /// is left out of a written config.
    #[serde(skip_serializing_if = "is_default_position_dive_gain")]
    pub position_dive_gain: f64,
}

fn is_default_flap_rate_weight(value: &f64) -> bool {
    *value == RewardConfig::default().flap_rate_weight
}

fn is_default_flap_max_hz(value: &f64) -> bool {
    *value == RewardConfig::default().flap_max_hz
}

fn is_default_flap_rate_scale_hz(value: &f64) -> bool {
    *value == RewardConfig::default().flap_rate_scale_hz
}

fn is_default_flap_rate_glide_share(value: &f64) -> bool {
    *value == RewardConfig::default().flap_rate_glide_share
}

fn is_default_glide_hold_weight(value: &f64) -> bool {
    *value == RewardConfig::default().glide_hold_weight
}

fn is_default_energy_turn_scale_degps(value: &f64) -> bool {
    *value == RewardConfig::default().energy_turn_scale_degps
}

fn is_default_glide_hold_turn_scale_degps(value: &f64) -> bool {
    *value == RewardConfig::default().glide_hold_turn_scale_degps
}

fn is_default_glide_hold_scale_deg(value: &f64) -> bool {
    *value == RewardConfig::default().glide_hold_scale_deg
}

fn is_default_smoothness_glide_stop_before_dive_s(value: &f64) -> bool {
    *value == RewardConfig::default().smoothness_glide_stop_before_dive_s
}

fn is_default_position_dive_gain(value: &f64) -> bool {
    *value == RewardConfig::default().position_dive_gain
}

/// Over how much speed (m/s) below `reward.smoothness_min_speed_mps` the smoothness weight falls to 0,
/// and below `reward.energy_min_speed_mps` the energy's price.
pub const SPEED_RAMP_MPS: f64 = 0.5;

/// The fastest clock (`observation.clock_hz`) a config may ask for: well under the 25 Hz a 50 Hz policy
/// can still tell from its samples.
pub const CLOCK_MAX_HZ: f64 = 20.0;

/// The share of a per-step weight kept at `speed` (m/s) by a floor of `min_speed`: 1 at or above it,
/// falling linearly to 0 over the [`SPEED_RAMP_MPS`] below it; 1 at every speed where
/// `min_speed` is 0 (off).
pub fn speed_ramp(min_speed: f64, speed: f64) -> f64 {
    if min_speed > 0.0 { (1.0 - (min_speed - speed) / SPEED_RAMP_MPS).clamp(0.0, 1.0) } else { 1.0 }
}

/// The sink rate from which `reward.smoothness_glide_gain` and `reward.energy_glide_gain` weigh in full
/// (m/s): the gentlest glide
/// commands sink 3.5 / 4.6 = 0.76 m/s (`reference.glide_speed_mps`, `reference.glide_ratio`).
pub const GLIDE_SINK_MPS: f64 = 0.5;

/// The steepest slope the glide gains count as a glide: horizontal over sink speed at
/// least this. The shipped model glides 4.6 : 1 (`flapper fly --controller glide`); longitudinal's dive
/// (3.8 m/s forward, 1.5 m/s down) is 2.5 : 1.
pub const GLIDE_MIN_RATIO: f64 = 3.5;

/// Paper III-F: 30 s episodes, 3 m error termination, attitude termination in stages 1-2.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct EpisodeConfig {
    /// Control steps before time-limit truncation (1500 = 30 s).
    pub max_steps: usize,
    /// Terminate when farther than this from the current target.
    pub max_position_error_m: f64,
    /// Terminate when |roll| or |pitch| exceeds `attitude_limit_deg` (stages 1-2).
    pub attitude_termination: bool,
    pub attitude_limit_deg: f64,
}

/// Paper III-B: references built from commands of forward speed, vertical speed and yaw rate, each
/// held `command_duration_s`; loops as pieces too.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ReferenceConfig {
    pub command_duration_s: f64,
    pub forward_speed_mps: Interval,
    pub vertical_speed_mps: Interval,
    pub yaw_rate_degps: Interval,
    /// Chance that a command slot holds a vertical loop (back-flip, Immelmann or roll-off-the-bottom).
    pub loop_probability: f64,
    /// Duration of a full loop; half loops take half of it.
    pub loop_duration_s: f64,
    /// Chance that a command slot holds a sharp level turn instead (paper Fig. 10a: 180 deg in 1.2 s),
    /// drawn after the loop.
    pub sharp_turn_probability: f64,
    /// Heading change of a sharp turn (deg), drawn from this range, left or right with equal chance.
    pub sharp_turn_deg: Interval,
    /// Duration of a sharp turn (s).
    pub sharp_turn_duration_s: Interval,
    /// Chance that a held command (not a loop or a sharp turn) flies at a speed drawn from
    /// `slow_speed_mps` instead of `forward_speed_mps`: slow level flight, climbs and descents get their
    /// own share of episodes while the manoeuvres keep the full speed range. 0 (the default) draws
    /// nothing extra, so configs without it generate exactly the references they always did.
    pub slow_probability: f64,
    /// The slow commands' forward speeds (m/s), used where `slow_probability` > 0.
    pub slow_speed_mps: Interval,
    /// Chance that a held command (not a loop or a sharp turn) is a straight descent at a glide slope:
    /// forward speed from `glide_speed_mps`, sinking at forward speed / a ratio from `glide_ratio`,
    /// a path the robot can fly with its wings held (the shipped model glides 4.6 : 1 at 3.8 m/s,
    /// `flapper fly --controller glide`). 0 (the default) draws nothing extra.
    pub glide_probability: f64,
    /// The glide commands' forward speeds (m/s), used where `glide_probability` > 0.
    pub glide_speed_mps: Interval,
    /// The glide commands' ratios of forward to sink speed, used where `glide_probability` > 0.
    pub glide_ratio: Interval,
    /// Chance that a held command (not a loop, a sharp turn or a glide) is a long straight and level one
    /// at a speed from `level_speed_mps`, held `level_duration_s`: slow level flight long enough that a
    /// slowly growing sideways weave costs what it costs on a long straight path (the shipped controller
    /// weaves +-1 m within 20 s at 3 m/s). 0 (the default) draws nothing extra.
    pub level_probability: f64,
    /// The level commands' forward speeds (m/s), used where `level_probability` > 0.
    pub level_speed_mps: Interval,
    /// How long a level command is held (s), used where `level_probability` > 0.
    pub level_duration_s: f64,
}

/// Paper III-E: the episode starts near the reference's start so the policy must recover and rejoin.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InitialStateConfig {
    /// Uniform offset from the reference's first point, per axis (x, y, z).
    pub position_offset_m: [f64; 3],
    /// Uniform offset of the launch speed from the reference's first speed.
    pub speed_offset_mps: f64,
    /// Nose-up pitch of the launch attitude (the flapping trim is near 20 deg).
    pub pitch_deg: f64,
    /// Uniform offset of roll, pitch and yaw (relative to the reference heading).
    pub attitude_offset_deg: f64,
    /// Training paths only: the share of episodes that start somewhere along the drawn path instead of
    /// at its beginning (inside a loop, halfway through a turn), on the path at its speed, with the
    /// attitude whose lift would bend the path there; the offsets above still apply. 0 by default (every
    /// episode starts at the path's beginning, and no random number is drawn for it). A policy that has
    /// never flown the top of a loop meets it only by getting there; starting there shows it at once
    /// (DeepMimic's reference state initialization). Needs `episode.attitude_termination = false` to be of
    /// use in the manoeuvres (an inverted start would end at once).
    pub path_start_probability: f64,
}

/// Paper III-E, Table III: per-episode dynamics randomization. A scale interval of [1, 1] or an
/// offset of 0 switches that item off; `enabled = false` switches all off.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RandomizationConfig {
    pub enabled: bool,
    /// The share of episodes that are randomized (when `enabled`); the others fly the nominal
    /// model in still air. 1 (every episode) by default, as the paper.
    pub episode_fraction: f64,
    pub joint_damping_scale: Interval,
    pub link_mass_scale: Interval,
    pub link_inertia_scale: Interval,
    /// Uniform offset of each link's centre of mass per axis (paper: 0.05 m; ours 5 mm: README, "Randomization").
    pub link_com_offset_m: f64,
    pub fluid_coefficient_scale: Interval,
    /// Which of the five fluid coefficients (blunt drag, slender drag, angular drag, Kutta lift, Magnus
    /// lift) `fluid_coefficient_scale` applies to; the others stay nominal (the robustness sweeps
    /// randomize one at a time). All five by default.
    pub fluid_coefficients_randomized: [bool; 5],
    pub added_mass_scale: Interval,
    pub added_inertia_scale: Interval,
    /// A steady wind (x, y, z) that every episode has, before the drawn part (m/s; zero by default).
    pub steady_wind_mps: [f64; 3],
    /// Uniform wind per axis (x, y, z), +- these values, on top of `steady_wind_mps`.
    pub wind_mps: [f64; 3],
}

impl Default for TaskConfig {
    fn default() -> Self {
        Self::stage(1).expect("stage 1 exists")
    }
}

impl Default for ControlConfig {
    fn default() -> Self {
        Self {
            substeps: 5,
            filter_cutoff_hz: 7.0,
            action_scale: 1.0,
            action_mode: ActionMode::JointTargets,
            flap_frequency_hz: [3.0, 8.0],
            oscillator_a2: OscillatorA2::Frequency,
            differential_flap: 0.0,
            flap_amplitude_max: 1.0,
            flap_shape_filter_hz: 0.0,
            flap_shape_rate_limit: 0.0,
            passive_feathering_s: 0.0,
        }
    }
}

impl Default for ObservationConfig {
    fn default() -> Self {
        Self { history_frames: 25, lookahead_steps: 30, clock_hz: 0.0 }
    }
}

impl RewardConfig {
    /// Whether the learner's smoothness term is weighed per step (by the turns ahead, the speed, the
    /// glide slope, or several of them).
    pub fn weighs_smoothness(&self) -> bool {
        self.smoothness_turn_scale_degps > 0.0
            || self.smoothness_min_speed_mps > 0.0
            || self.smoothness_glide_gain > 0.0
            || self.smoothness_dive_share < 1.0
    }
}

impl Default for RewardConfig {
    fn default() -> Self {
        Self {
            position_weight: 0.5,
            body_rate_weight: 0.1,
            level_weight: 0.2,
            energy_weight: 0.05,
            position_scale_m: 1.0,
            body_rate_scale_radps: 3.0,
            level_scale_rad: 0.5,
            energy_scale_w: 20.0,
            action_rate_weight: 0.0,
            action_rate_scale: 1.0,
            flap_rate_weight: 0.0,
            flap_max_hz: 5.5,
            flap_rate_scale_hz: 0.5,
            flap_rate_glide_share: 1.0,
            glide_hold_weight: 0.0,
            feathering_weight: 0.0,
            glide_hold_scale_deg: crate::flap_rhythm::HELD_FLAP_RANGE_DEG,
            glide_hold_turn_scale_degps: 0.0,
            smoothness_turn_scale_degps: 0.0,
            smoothness_min_speed_mps: 0.0,
            smoothness_glide_gain: 0.0,
            smoothness_glide_stop_before_dive_s: 0.0,
            smoothness_dive_share: 1.0,
            energy_min_speed_mps: 0.0,
            energy_glide_gain: 0.0,
            energy_dive_share: 1.0,
            energy_turn_scale_degps: 0.0,
            position_dive_gain: 0.0,
        }
    }
}

impl Default for EpisodeConfig {
    fn default() -> Self {
        Self { max_steps: 1500, max_position_error_m: 3.0, attitude_termination: true, attitude_limit_deg: 90.0 }
    }
}

impl Default for ReferenceConfig {
    /// Stage 1: constant forward flight at the paper's 3.8 m/s.
    fn default() -> Self {
        Self {
            command_duration_s: 3.0,
            forward_speed_mps: [flapper_sim::CRUISE_SPEED_MPS; 2],
            vertical_speed_mps: [0.0, 0.0],
            yaw_rate_degps: [0.0, 0.0],
            loop_probability: 0.0,
            loop_duration_s: 3.0,
            sharp_turn_probability: 0.0,
            sharp_turn_deg: [90.0, 180.0],
            sharp_turn_duration_s: [1.2, 2.4],
            slow_probability: 0.0,
            slow_speed_mps: [2.5, 3.5],
            glide_probability: 0.0,
            glide_speed_mps: [3.5, 4.2],
            glide_ratio: [4.0, 4.6],
            level_probability: 0.0,
            level_speed_mps: [2.5, 3.5],
            level_duration_s: 8.0,
        }
    }
}

impl Default for InitialStateConfig {
    fn default() -> Self {
        Self {
            position_offset_m: [0.5, 0.5, 0.5],
            speed_offset_mps: 0.5,
            pitch_deg: 20.0,
            attitude_offset_deg: 10.0,
            path_start_probability: 0.0,
        }
    }
}

/// The paper's centre-of-mass range. Our default is smaller; see [`RandomizationConfig::default`].
pub const PAPER_COM_OFFSET_M: f64 = 0.05;

impl Default for RandomizationConfig {
    /// Table III, switched off (stage 4 switches it on). The centre-of-mass offset defaults to 5 mm,
    /// not the paper's 50 mm: the glide of this model changes its ratio by about 0.5 per 2 mm of
    /// wing position, and +-50 mm puts the centre of mass ahead of the wing's leading edge or behind
    /// its mid-chord (README, "Randomization"). `PAPER_COM_OFFSET_M` keeps the paper's value.
    fn default() -> Self {
        Self {
            enabled: false,
            episode_fraction: 1.0,
            joint_damping_scale: [0.9, 1.1],
            link_mass_scale: [0.9, 1.1],
            link_inertia_scale: [0.9, 1.1],
            link_com_offset_m: 0.005,
            fluid_coefficient_scale: [0.7, 1.3],
            fluid_coefficients_randomized: [true; 5],
            added_mass_scale: [0.9, 1.1],
            added_inertia_scale: [0.9, 1.1],
            steady_wind_mps: [0.0; 3],
            wind_mps: [2.0, 2.0, 1.5],
        }
    }
}

impl TaskConfig {
    /// The curriculum preset for `stage` (paper III-A):
    /// 1 constant forward flight; 2 climbing and diving at variable speeds; 3 turning and arbitrary
    /// manoeuvres including loops (no attitude termination); 4 stage 3 plus dynamics randomization.
    pub fn stage(stage: i64) -> Result<Self, ConfigError> {
        let mut config = Self {
            stage: 1,
            control: ControlConfig::default(),
            observation: ObservationConfig::default(),
            reward: RewardConfig::default(),
            episode: EpisodeConfig::default(),
            reference: ReferenceConfig::default(),
            initial_state: InitialStateConfig::default(),
            randomization: RandomizationConfig::default(),
        };
        match stage {
            1 => {}
            2 => {
                config.reference.forward_speed_mps = [3.0, 5.0];
                config.reference.vertical_speed_mps = [-1.5, 1.0];
            }
            3 | 4 => {
                config.reference.forward_speed_mps = [3.0, 5.5];
                config.reference.vertical_speed_mps = [-1.5, 1.0];
                config.reference.yaw_rate_degps = [-60.0, 60.0];
                config.reference.loop_probability = 0.15;
                config.reference.sharp_turn_probability = 0.15;
                config.episode.attitude_termination = false;
                config.randomization.enabled = stage == 4;
            }
            other => return Err(ConfigError::UnknownStage(other)),
        }
        config.stage = stage as u8;
        Ok(config)
    }

    /// Reads a TOML file: the optional top-level `stage` picks the preset (default 1), every other key
    /// overrides it. Unknown keys and out-of-range values are errors naming them.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| ConfigError::Read { path: path.display().to_string(), source })?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// As [`TaskConfig::load`], from TOML text; `origin` names it in errors.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, ConfigError> {
        let parse = |message: String| ConfigError::Parse { path: origin.to_owned(), message };
        let overrides: toml::Table = text.parse().map_err(|e: toml::de::Error| parse(e.to_string()))?;
        let stage = match overrides.get("stage") {
            None => 1,
            Some(toml::Value::Integer(n)) => *n,
            Some(other) => return Err(parse(format!("stage must be an integer 1-4, got {other}"))),
        };
        let preset = Self::stage(stage)?;
        let mut merged = toml::Table::try_from(&preset).map_err(|e| parse(e.to_string()))?;
        merge(&mut merged, overrides);
        let config: Self = toml::Value::Table(merged).try_into().map_err(|e: toml::de::Error| parse(e.to_string()))?;
        config.validate()?;
        Ok(config)
    }

    /// Rejects values no run could use: every number finite, counts and durations bounded so that
    /// no buffer outgrows memory (at most 100 000 steps of 30 ms-scale work per episode, 1000 history
    /// frames or lookahead points, 100 substeps), offsets and rates within what the robot could meet.
    pub fn validate(&self) -> Result<(), ConfigError> {
        self.check_counts()?;
        self.check_scalars()?;
        self.check_intervals()?;
        self.check_randomization()
    }

    /// Counts: at least 1, at most a bound no run needs more than.
    fn check_counts(&self) -> Result<(), ConfigError> {
        for (key, value, max) in [
            ("control.substeps", self.control.substeps, 100),
            ("observation.history_frames", self.observation.history_frames, 1000),
            ("observation.lookahead_steps", self.observation.lookahead_steps, 1000),
            ("episode.max_steps", self.episode.max_steps, 100_000),
        ] {
            if value > max {
                return Err(ConfigError::TooLarge { key, value: value.to_string(), max: max.to_string() });
            }
            if value == 0 {
                return Err(ConfigError::Invalid { key, value: "0".into(), why: "must be at least 1" });
            }
        }
        Ok(())
    }

    /// Every single number with its closed range (NaN is refused by every range).
    fn check_scalars(&self) -> Result<(), ConfigError> {
        let (i, r, f, g) = (&self.initial_state, &self.reward, &self.reference, &self.randomization);
        for (key, value, low, high) in [
            ("initial_state.position_offset_m[0]", i.position_offset_m[0], 0.0, 10.0),
            ("initial_state.position_offset_m[1]", i.position_offset_m[1], 0.0, 10.0),
            ("initial_state.position_offset_m[2]", i.position_offset_m[2], 0.0, 10.0),
            ("initial_state.speed_offset_mps", i.speed_offset_mps, 0.0, 10.0),
            ("initial_state.pitch_deg", i.pitch_deg, -90.0, 90.0),
            ("initial_state.attitude_offset_deg", i.attitude_offset_deg, 0.0, 180.0),
            ("initial_state.path_start_probability", i.path_start_probability, 0.0, 1.0),
            ("episode.attitude_limit_deg", self.episode.attitude_limit_deg, 1.0, 180.0),
            ("episode.max_position_error_m", self.episode.max_position_error_m, 0.01, 100.0),
            ("reference.command_duration_s", f.command_duration_s, 0.1, 60.0),
            ("reference.loop_duration_s", f.loop_duration_s, 1.0, 60.0),
            ("reference.loop_probability", f.loop_probability, 0.0, 1.0),
            ("reference.sharp_turn_probability", f.sharp_turn_probability, 0.0, 1.0),
            ("reference.slow_probability", f.slow_probability, 0.0, 1.0),
            ("reference.glide_probability", f.glide_probability, 0.0, 1.0),
            ("reference.level_probability", f.level_probability, 0.0, 1.0),
            ("reference.level_duration_s", f.level_duration_s, 0.1, 600.0),
            ("control.filter_cutoff_hz", self.control.filter_cutoff_hz, 0.01, 1000.0),
            ("observation.clock_hz", self.observation.clock_hz, 0.0, CLOCK_MAX_HZ),
            ("control.action_scale", self.control.action_scale, 1e-6, 1.0),
            ("control.differential_flap", self.control.differential_flap, 0.0, 1.0),
            ("control.flap_amplitude_max", self.control.flap_amplitude_max, 0.1, 3.0),
            ("control.flap_shape_filter_hz", self.control.flap_shape_filter_hz, 0.0, 100.0),
            ("control.flap_shape_rate_limit", self.control.flap_shape_rate_limit, 0.0, 1000.0),
            ("control.passive_feathering_s", self.control.passive_feathering_s, 0.0, 0.2),
            ("reward.position_scale_m", r.position_scale_m, 1e-3, 1e3),
            ("reward.body_rate_scale_radps", r.body_rate_scale_radps, 1e-3, 1e3),
            ("reward.level_scale_rad", r.level_scale_rad, 1e-3, 1e3),
            ("reward.energy_scale_w", r.energy_scale_w, 1e-3, 1e5),
            ("reward.position_weight", r.position_weight, 0.0, 1e3),
            ("reward.body_rate_weight", r.body_rate_weight, 0.0, 1e3),
            ("reward.level_weight", r.level_weight, 0.0, 1e3),
            ("reward.energy_weight", r.energy_weight, 0.0, 1e3),
            ("reward.action_rate_weight", r.action_rate_weight, 0.0, 1e3),
            ("reward.action_rate_scale", r.action_rate_scale, 1e-3, 1e3),
            ("reward.flap_rate_weight", r.flap_rate_weight, 0.0, 1e3),
            ("reward.flap_max_hz", r.flap_max_hz, 0.1, 100.0),
            ("reward.flap_rate_scale_hz", r.flap_rate_scale_hz, 1e-3, 100.0),
            ("reward.flap_rate_glide_share", r.flap_rate_glide_share, 0.0, 1.0),
            ("reward.glide_hold_weight", r.glide_hold_weight, 0.0, 1e3),
            ("reward.feathering_weight", r.feathering_weight, 0.0, 1e3),
            ("reward.glide_hold_scale_deg", r.glide_hold_scale_deg, 1e-3, 360.0),
            ("reward.smoothness_turn_scale_degps", r.smoothness_turn_scale_degps, 0.0, 1e5),
            ("reward.glide_hold_turn_scale_degps", r.glide_hold_turn_scale_degps, 0.0, 1e5),
            ("reward.smoothness_min_speed_mps", r.smoothness_min_speed_mps, 0.0, 50.0),
            ("reward.energy_min_speed_mps", r.energy_min_speed_mps, 0.0, 50.0),
            ("reward.smoothness_glide_gain", r.smoothness_glide_gain, 0.0, 1e3),
            ("reward.smoothness_glide_stop_before_dive_s", r.smoothness_glide_stop_before_dive_s, 0.0, 60.0),
            ("reward.energy_glide_gain", r.energy_glide_gain, 0.0, 1e3),
            ("reward.energy_dive_share", r.energy_dive_share, 0.0, 1.0),
            ("reward.energy_turn_scale_degps", r.energy_turn_scale_degps, 0.0, 1e5),
            ("reward.smoothness_dive_share", r.smoothness_dive_share, 0.0, 1.0),
            ("reward.position_dive_gain", r.position_dive_gain, 0.0, 1e3),
            ("randomization.episode_fraction", g.episode_fraction, 0.0, 1.0),
            ("randomization.link_com_offset_m", g.link_com_offset_m, 0.0, 0.1),
            ("randomization.wind_mps[0]", g.wind_mps[0], 0.0, 20.0),
            ("randomization.wind_mps[1]", g.wind_mps[1], 0.0, 20.0),
            ("randomization.wind_mps[2]", g.wind_mps[2], 0.0, 20.0),
            ("randomization.steady_wind_mps[0]", g.steady_wind_mps[0], -20.0, 20.0),
            ("randomization.steady_wind_mps[1]", g.steady_wind_mps[1], -20.0, 20.0),
            ("randomization.steady_wind_mps[2]", g.steady_wind_mps[2], -20.0, 20.0),
        ] {
            if !(value >= low && value <= high) {
                return Err(ConfigError::OutOfRange { key, value: value.to_string(), low, high });
            }
        }
        Ok(())
    }

    /// The intervals (the reference generator's and the oscillator's frequencies): ordered, finite, and
    /// within their range.
    fn check_intervals(&self) -> Result<(), ConfigError> {
        let f = &self.reference;
        let fastest = crate::reference::csv_file::MAX_REFERENCE_SPEED_MPS;
        for (key, interval, low, high) in [
            ("reference.forward_speed_mps", f.forward_speed_mps, 0.1, fastest),
            ("reference.vertical_speed_mps", f.vertical_speed_mps, -15.0, 15.0),
            ("reference.yaw_rate_degps", f.yaw_rate_degps, -720.0, 720.0),
            ("reference.sharp_turn_deg", f.sharp_turn_deg, 0.0, 360.0),
            ("reference.sharp_turn_duration_s", f.sharp_turn_duration_s, 0.2, 60.0),
            ("reference.slow_speed_mps", f.slow_speed_mps, 0.1, fastest),
            ("reference.glide_speed_mps", f.glide_speed_mps, 0.1, fastest),
            ("reference.glide_ratio", f.glide_ratio, 0.5, 100.0),
            ("reference.level_speed_mps", f.level_speed_mps, 0.1, fastest),
            ("control.flap_frequency_hz", self.control.flap_frequency_hz, 0.1, 20.0),
        ] {
            check_interval(key, interval)?;
            if !(interval[0] >= low && interval[1] <= high) {
                return Err(ConfigError::OutOfRange { key, value: format!("{interval:?}"), low, high });
            }
        }
        Ok(())
    }

    /// The randomization's scale intervals: ordered, positive, at most 10.
    fn check_randomization(&self) -> Result<(), ConfigError> {
        let g = &self.randomization;
        for (key, interval) in [
            ("randomization.joint_damping_scale", g.joint_damping_scale),
            ("randomization.link_mass_scale", g.link_mass_scale),
            ("randomization.link_inertia_scale", g.link_inertia_scale),
            ("randomization.fluid_coefficient_scale", g.fluid_coefficient_scale),
            ("randomization.added_mass_scale", g.added_mass_scale),
            ("randomization.added_inertia_scale", g.added_inertia_scale),
        ] {
            check_interval(key, interval)?;
            if !(interval[0] > 0.0 && interval[1] <= 10.0) {
                return Err(ConfigError::Invalid {
                    key,
                    value: format!("{interval:?}"),
                    why: "scales must lie in (0, 10]",
                });
            }
        }
        Ok(())
    }

    /// Seconds of simulated time per policy step.
    pub fn control_period_s(&self, timestep_s: f64) -> f64 {
        self.control.substeps as f64 * timestep_s
    }
}

fn check_interval(key: &'static str, interval: Interval) -> Result<(), ConfigError> {
    if interval.iter().all(|v| v.is_finite()) && interval[0] <= interval[1] {
        Ok(())
    } else {
        Err(ConfigError::Invalid { key, value: format!("{interval:?}"), why: "must be [low, high] with low <= high" })
    }
}

/// Overwrites `base` with `overrides`, table by table.
fn merge(base: &mut toml::Table, overrides: toml::Table) {
    for (key, value) in overrides {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(inner)), toml::Value::Table(over)) => merge(inner, over),
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_the_papers() {
        let c = TaskConfig::default();
        assert_eq!((c.control.substeps, c.control.filter_cutoff_hz), (5, 7.0));
        assert_eq!((c.observation.history_frames, c.observation.lookahead_steps), (25, 30));
        let r = &c.reward;
        assert_eq!([r.position_weight, r.body_rate_weight, r.level_weight, r.energy_weight], [0.5, 0.1, 0.2, 0.05]);
        assert_eq!((c.episode.max_steps, c.episode.max_position_error_m), (1500, 3.0));
        assert_eq!(c.randomization.fluid_coefficient_scale, [0.7, 1.3]);
        assert_eq!(c.randomization.wind_mps, [2.0, 2.0, 1.5]);
        c.validate().unwrap();
    }

    #[test]
    fn stages_change_the_task_not_the_layout() {
        let stages: Vec<TaskConfig> = (1..=4).map(|s| TaskConfig::stage(s).unwrap()).collect();
        assert!(stages[0].episode.attitude_termination && stages[1].episode.attitude_termination);
        assert!(!stages[2].episode.attitude_termination && !stages[3].episode.attitude_termination);
        assert!(stages[2].reference.yaw_rate_degps[1] > 0.0 && stages[2].reference.loop_probability > 0.0);
        assert!(stages[3].randomization.enabled && !stages[2].randomization.enabled);
        assert!(
            stages[1].reference.vertical_speed_mps[0] < 0.0 && stages[0].reference.vertical_speed_mps == [0.0, 0.0]
        );
        for s in &stages {
            assert_eq!(s.observation, stages[0].observation);
            assert_eq!(s.control, stages[0].control);
        }
        assert!(matches!(TaskConfig::stage(5), Err(ConfigError::UnknownStage(5))));
    }

    #[test]
    fn toml_overrides_a_stage_preset() {
        let c = TaskConfig::from_toml(
            "stage = 2\n[reward]\nposition_scale_m = 0.5\n[control]\nfilter_cutoff_hz = 5.0\n",
            "t.toml",
        )
        .unwrap();
        assert_eq!(c.stage, 2);
        assert_eq!(c.reward.position_scale_m, 0.5);
        assert_eq!(c.reward.position_weight, 0.5, "untouched keys keep the preset");
        assert_eq!(c.control.filter_cutoff_hz, 5.0);
        assert_eq!(c.reference.vertical_speed_mps, [-1.5, 1.0]);
        assert_eq!(c.control.action_mode, ActionMode::JointTargets, "the paper's actions by default");
        let c = TaskConfig::from_toml("stage = 4\n[control]\naction_mode = \"flap_oscillator\"\n", "t.toml").unwrap();
        assert_eq!(c.control.action_mode, ActionMode::FlapOscillator);
        assert!(c.randomization.enabled, "the stage preset stays");
    }

    #[test]
    fn unknown_keys_and_bad_values_are_named() {
        let refused = |text: &str| TaskConfig::from_toml(text, "bad.toml").unwrap_err().to_string();
        let err = refused("[reward]\nposition_wieght = 0.3\n");
        assert!(err.contains("bad.toml") && err.contains("position_wieght"), "{err}");
        let err = refused("[episode]\nmax_position_error_m = -1.0\n");
        assert!(err.contains("episode.max_position_error_m") && err.contains("-1"), "{err}");
        let err = refused("[reference]\nglide_ratio = [4.0, 0.2]\n");
        assert!(err.contains("reference.glide_ratio"), "{err}");
        let err = refused("[reference]\nglide_probability = -0.1\n");
        assert!(err.contains("reference.glide_probability") && err.contains("-0.1"), "{err}");
        let err = refused("[reference]\nslow_probability = 1.5\n");
        assert!(err.contains("reference.slow_probability") && err.contains("1.5"), "{err}");
        let err = refused("[reference]\nslow_speed_mps = [3.0, 2.0]\n");
        assert!(err.contains("reference.slow_speed_mps"), "{err}");
        let err = refused("[control]\naction_mode = \"flapping\"\n");
        assert!(err.contains("bad.toml") && err.contains("flapping") && err.contains("flap_oscillator"), "{err}");
        let err = refused("[control]\nflap_frequency_hz = [8.0, 3.0]\n");
        assert!(err.contains("control.flap_frequency_hz"), "{err}");
        let err = refused("[control]\nflap_frequency_hz = [0.0, 3.0]\n");
        assert!(err.contains("control.flap_frequency_hz"), "{err}");
        let err = refused("[control]\ndifferential_flap = 1.5\n");
        assert!(err.contains("control.differential_flap") && err.contains("1.5"), "{err}");
        let err = refused("[reward]\naction_rate_scale = 0.0\n");
        assert!(err.contains("reward.action_rate_scale") && err.contains("= 0"), "{err}");
        let err = refused("[reward]\nflap_rate_glide_share = 2\n");
        assert!(err.contains("reward.flap_rate_glide_share") && err.contains("= 2"), "{err}");
        let err = refused("[reward]\nflap_max_hz = 0\n");
        assert!(err.contains("reward.flap_max_hz") && err.contains("= 0"), "{err}");
        let err = refused("[reward]\nglide_hold_weight = -0.2\n");
        assert!(err.contains("reward.glide_hold_weight") && err.contains("-0.2"), "{err}");
        let err = refused("[reward]\nglide_hold_scale_deg = 0\n");
        assert!(err.contains("reward.glide_hold_scale_deg") && err.contains("= 0"), "{err}");
        for (clock, shown) in [("-1", "= -1"), ("25", "= 25"), ("nan", "= NaN")] {
            let err = refused(&format!("[observation]\nclock_hz = {clock}\n"));
            assert!(err.contains("observation.clock_hz") && err.contains(shown), "{err}");
        }
        let err = refused("[reward]\naction_rate_weight = -1\n");
        assert!(err.contains("reward.action_rate_weight") && err.contains("-1"), "{err}");
        let err = refused("[reward]\nenergy_dive_share = 1.5\n");
        assert!(err.contains("reward.energy_dive_share") && err.contains("1.5"), "{err}");
        let err = refused("[reward]\nsmoothness_glide_stop_before_dive_s = -0.5\n");
        assert!(err.contains("reward.smoothness_glide_stop_before_dive_s") && err.contains("-0.5"), "{err}");
        let err = refused("[reward]\nsmoothness_dive_share = -0.5\n");
        assert!(err.contains("reward.smoothness_dive_share") && err.contains("-0.5"), "{err}");
        let err = refused("[reward]\nenergy_glide_gain = -2\n");
        assert!(err.contains("reward.energy_glide_gain") && err.contains("-2"), "{err}");
        let err = refused("[reward]\nsmoothness_turn_scale_degps = -30\n");
        assert!(err.contains("reward.smoothness_turn_scale_degps") && err.contains("-30"), "{err}");
        let err = refused("[reward]\nsmoothness_min_speed_mps = -3\n");
        assert!(err.contains("reward.smoothness_min_speed_mps") && err.contains("-3"), "{err}");
        let err = refused("[reward]\nsmoothness_glide_gain = -1\n");
        assert!(err.contains("reward.smoothness_glide_gain") && err.contains("-1"), "{err}");
        let err = refused("[reward]\nenergy_min_speed_mps = -2.5\n");
        assert!(err.contains("reward.energy_min_speed_mps") && err.contains("-2.5"), "{err}");
        let err = refused("[reference]\nlevel_probability = 1.5\n");
        assert!(err.contains("reference.level_probability") && err.contains("1.5"), "{err}");
        let err = refused("[reference]\nlevel_speed_mps = [3.5, 2.5]\n");
        assert!(err.contains("reference.level_speed_mps"), "{err}");
        let err = refused("[control]\nflap_shape_rate_limit = -2\n");
        assert!(err.contains("control.flap_shape_rate_limit") && err.contains("-2"), "{err}");
        let err = refused("stage = 9\n");
        assert!(err.contains("stage 9"), "{err}");
        let err = refused("[reference]\nforward_speed_mps = [5.0, 3.0]\n");
        assert!(err.contains("forward_speed_mps"), "{err}");
        assert!(TaskConfig::from_toml("[control\n", "broken.toml").unwrap_err().to_string().contains("broken.toml"));
    }

    #[test]
    fn non_finite_and_unbounded_values_are_named_with_their_range() {
        for (text, key) in [
            ("[initial_state]\nspeed_offset_mps = inf\n", "initial_state.speed_offset_mps"),
            ("[initial_state]\nattitude_offset_deg = nan\n", "initial_state.attitude_offset_deg"),
            ("[initial_state]\nposition_offset_m = [0.5, inf, 0.5]\n", "initial_state.position_offset_m[1]"),
            ("[initial_state]\npitch_deg = nan\n", "initial_state.pitch_deg"),
            ("[episode]\nmax_steps = 1000000000000\n", "episode.max_steps"),
            ("[episode]\nattitude_limit_deg = 0.0\n", "episode.attitude_limit_deg"),
            ("[control]\nsubsteps = 1000000000000\n", "control.substeps"),
            ("[observation]\nhistory_frames = 1000000000000\n", "observation.history_frames"),
            ("[reference]\ncommand_duration_s = inf\n", "reference.command_duration_s"),
            ("[reference]\nloop_duration_s = 1e9\n", "reference.loop_duration_s"),
            ("[reference]\nyaw_rate_degps = [-1e300, 0.0]\n", "reference.yaw_rate_degps"),
            ("[randomization]\nlink_mass_scale = [0.9, 1e300]\n", "randomization.link_mass_scale"),
        ] {
            let err = TaskConfig::from_toml(text, "x.toml").unwrap_err().to_string();
            assert!(err.contains(key), "{text}: {err}");
        }
        // The paper's stages all pass.
        for stage in 1..=4 {
            TaskConfig::stage(stage).unwrap().validate().unwrap();
        }
    }
}
