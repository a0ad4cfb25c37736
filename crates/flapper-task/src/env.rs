//! One trajectory-tracking environment: the robot, its reference, the observation history and the
//! episode's bookkeeping. The vectorized environments step many of these in parallel.

use std::sync::Arc;

use flapper_sim::{ActuatedJoint, InitialState, ModelError, Quat, RobotModel, Vec3, quat_from_euler, quat_to_euler};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::action::{ACTION_SIZE, ActionMap, OscillatorState};
use crate::config::{GLIDE_MIN_RATIO, GLIDE_SINK_MPS, TaskConfig, speed_ramp};
use crate::control_loop::{ControlLoop, ControlLoopState};
use crate::flap_rhythm::{FlapRhythm, FlapSwing, StrokeFeathering};
use crate::observation::{Frame, ObservationBuilder, ObservationLayout, read_frame};
use crate::randomization::{DrawnDynamics, randomize};
use crate::reference::Reference;
use crate::reference::generator::procedural;
use crate::reward::{RewardInputs, RewardTerms};
use crate::termination::{EpisodeEnd, check_failure};

/// Where each episode's reference comes from.
#[derive(Debug, Clone)]
pub enum ReferenceSource {
    /// A new seeded random path per episode, from the config's `reference` ranges (training).
    Procedural,
    /// The same path every episode (evaluation: a named reference or a CSV).
    Fixed(Arc<Reference>),
}

/// A start along the path leaves at least this much of it to fly (two of the paper's 3 s commands).
pub const PATH_START_MIN_REMAINING_S: f64 = 6.0;

/// Gravity's acceleration (m/s^2), for the attitude a path asks.
const GRAVITY_MPS2: f64 = 9.81;

/// The attitude a path asks at its first point: body x along the direction of travel, body z (the lift's
/// side) along the part of the specific force (the path's acceleration plus gravity's support) across it;
/// world up across the path where that part vanishes (straight flight), +y where the path is vertical too.
/// Level straight flight gives a level attitude; a coordinated turn a bank into it; the top of a tight loop
/// an inverted one.
pub fn path_frame(reference: &Reference) -> Quat {
    let forward = reference.direction(0);
    let acceleration = (reference.velocity(2) - reference.velocity(0)) / (2.0 * reference.dt_s());
    let specific_force = acceleration + Vec3::Z * GRAVITY_MPS2;
    let across = |v: Vec3| v - forward * v.dot(forward);
    let up = across(specific_force)
        .try_normalize()
        .or_else(|| across(Vec3::Z).try_normalize())
        .unwrap_or_else(|| forward.any_orthonormal_vector());
    let left = up.cross(forward);
    Quat::from_mat3(&glam::DMat3::from_cols(forward, left, up)).normalize()
}

/// The result of one control step.
#[derive(Debug, Clone, Copy)]
pub struct StepResult {
    pub reward: f64,
    /// Distance from the reference's current target after the step (m).
    pub position_error_m: f64,
    pub terms: RewardTerms,
    /// Set when the episode ended at this step.
    pub end: Option<EpisodeEnd>,
}

/// Summary of a finished episode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EpisodeInfo {
    pub env_index: usize,
    pub episode_return: f64,
    pub length: usize,
    /// Sum over the episode of each term's kernel value (unweighted).
    pub term_sums: RewardTerms,
    pub end: EpisodeEnd,
}

/// An environment mid-episode, enough to continue it bit for bit: the random stream as it was when the
/// episode began (replaying the reset redraws the same reference, dynamics and start) and the state
/// that has evolved since. Training checkpoints hold one per environment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnvSnapshot {
    rng_at_reset: ChaCha8Rng,
    control: ControlLoopState,
    history: Vec<Frame>,
    step: usize,
    time_limit_steps: usize,
    previous_action: [f32; ACTION_SIZE],
    /// The flapping oscillator (`flap_oscillator` actions; all 0 in snapshots from before it).
    #[serde(default)]
    oscillator: OscillatorState,
    /// The flap's rhythm (`reward.flap_rate_weight`; the default in snapshots from before it).
    #[serde(default, skip_serializing_if = "FlapRhythm::is_unused")]
    flap_rhythm: FlapRhythm,
    /// The flap's swing (`reward.glide_hold_weight`; likewise).
    #[serde(default, skip_serializing_if = "FlapSwing::is_unused")]
    flap_swing: FlapSwing,
    /// The stroke's feathering (`reward.feathering_weight`; likewise).
    #[serde(default, skip_serializing_if = "StrokeFeathering::is_unused")]
    feathering: StrokeFeathering,
    episode_return: f64,
    term_sums: RewardTerms,
}

/// A fixed reference must be sampled at the control period: point k is the target at step k.
fn check_reference_step(source: &ReferenceSource, period_s: f64) -> Result<(), ModelError> {
    match source {
        ReferenceSource::Fixed(reference) if (reference.dt_s() - period_s).abs() > 1e-9 * period_s => {
            Err(ModelError::InvalidValue {
                what: format!("reference '{}' step", reference.name()),
                value: format!("{} s", reference.dt_s()),
                why: "differs from the control period of this model and task: resample it at the control period",
            })
        }
        _ => Ok(()),
    }
}

/// Whether a reference velocity (z up) dives steeper than the slope the robot can glide: it sinks, with
/// less than [`GLIDE_MIN_RATIO`] times its sink speed along the ground.
fn is_steeper_than_glide(velocity: Vec3) -> bool {
    let sink = -velocity.z;
    sink > 0.0 && velocity.x.hypot(velocity.y) < GLIDE_MIN_RATIO * sink
}

pub struct FlightEnv {
    config: Arc<TaskConfig>,
    control: ControlLoop,
    actions: ActionMap,
    observation: ObservationBuilder,
    source: ReferenceSource,
    reference: Arc<Reference>,
    rng: ChaCha8Rng,
    /// `rng` as it was when the current episode began.
    rng_at_reset: ChaCha8Rng,
    index: usize,
    step: usize,
    /// Steps after which this episode is truncated: `episode.max_steps`, except for a first episode
    /// shortened by [`FlightEnv::shorten_episode`].
    time_limit_steps: usize,
    previous_action: [f32; ACTION_SIZE],
    /// The flapping oscillator (`flap_oscillator` actions only).
    oscillator: OscillatorState,
    /// The left flap's frequency as flown, for r_flap_rate (read only when it is weighed).
    flap_rhythm: FlapRhythm,
    /// The left flap's swing over the last 0.4 s, for r_glide_hold (likewise).
    flap_swing: FlapSwing,
    /// The wings' pitch against their flap rate over the last 0.4 s, for r_feathering (likewise).
    feathering: StrokeFeathering,
    episode_return: f64,
    term_sums: RewardTerms,
    drawn: DrawnDynamics,
}

impl FlightEnv {
    /// Environment `index` of a run seeded `seed`: its random stream depends on both and nothing else.
    pub fn new(
        robot: &RobotModel,
        config: Arc<TaskConfig>,
        source: ReferenceSource,
        seed: u64,
        index: usize,
    ) -> Result<Self, ModelError> {
        let sim = robot.instantiate()?;
        let control = ControlLoop::new(sim, config.control);
        let actions = ActionMap::new(control.sim(), &config.control, control.control_period_s());
        let layout = ObservationLayout::of(&config.observation);
        let observation = ObservationBuilder::new(layout, config.observation.clock_hz, control.control_period_s());
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(index as u64);
        check_reference_step(&source, control.control_period_s())?;
        let placeholder = Arc::new(Reference::new("none", control.control_period_s(), vec![Vec3::ZERO]));
        let mut env = Self {
            config,
            control,
            actions,
            observation,
            source,
            reference: placeholder,
            rng_at_reset: rng.clone(),
            rng,
            index,
            step: 0,
            time_limit_steps: 0,
            previous_action: [0.0; ACTION_SIZE],
            oscillator: OscillatorState::default(),
            flap_rhythm: FlapRhythm::default(),
            flap_swing: FlapSwing::default(),
            feathering: StrokeFeathering::default(),
            episode_return: 0.0,
            term_sums: RewardTerms::default(),
            drawn: DrawnDynamics::default(),
        };
        env.reset()?;
        Ok(env)
    }

    /// Reseeds the random stream from (`seed`, this environment's index) and starts a new episode.
    pub fn restart(&mut self, seed: u64) -> Result<(), ModelError> {
        self.rng = ChaCha8Rng::seed_from_u64(seed);
        self.rng.set_stream(self.index as u64);
        self.reset()
    }

    /// Flies `source` from now on, starting a new episode on it.
    pub fn set_reference_source(&mut self, source: ReferenceSource) -> Result<(), ModelError> {
        check_reference_step(&source, self.control.control_period_s())?;
        self.source = source;
        self.reset()
    }

    pub fn observation_layout(&self) -> ObservationLayout {
        self.observation.layout()
    }

    /// Starts a new episode: reference, dynamics, initial state.
    pub fn reset(&mut self) -> Result<(), ModelError> {
        self.rng_at_reset = self.rng.clone();
        self.time_limit_steps = self.config.episode.max_steps;
        let dt = self.control.control_period_s();
        let lookahead = self.config.observation.lookahead_steps;
        self.reference = match &self.source {
            ReferenceSource::Fixed(reference) => reference.clone(),
            ReferenceSource::Procedural => {
                let path = procedural(
                    &self.config.reference,
                    self.config.episode.max_steps as f64 * dt,
                    (lookahead + 1) as f64 * dt,
                    dt,
                    &mut self.rng,
                );
                Arc::new(self.draw_path_start(path, lookahead))
            }
        };
        self.drawn = randomize(self.control.sim_mut(), &self.config.randomization, &mut self.rng)?;
        let initial = self.draw_initial_state();
        self.control.reset(&initial);
        self.step = 0;
        self.previous_action = self.actions.at_rest(&initial.joint_positions_rad);
        self.oscillator = self.actions.oscillator_at_rest(&self.previous_action);
        self.flap_rhythm = FlapRhythm::default();
        self.flap_swing = FlapSwing::default();
        self.feathering = StrokeFeathering::default();
        self.episode_return = 0.0;
        self.term_sums = RewardTerms::default();
        self.observation.reset(read_frame(self.control.sim(), &self.previous_action));
        Ok(())
    }

    /// With `initial_state.path_start_probability`, the drawn path from a random step on (the episode
    /// starts there); else the path as drawn. Draws nothing when the probability is 0.
    fn draw_path_start(&mut self, path: Reference, lookahead_steps: usize) -> Reference {
        let probability = self.config.initial_state.path_start_probability;
        if probability <= 0.0 || !self.rng.random_bool(probability) {
            return path;
        }
        let remaining = (PATH_START_MIN_REMAINING_S / path.dt_s()).round() as usize;
        let last_start = path.steps_with_full_lookahead(lookahead_steps).saturating_sub(remaining);
        if last_start == 0 {
            return path;
        }
        let start = self.rng.random_range(0..=last_start);
        Reference::new(path.name(), path.dt_s(), path.points()[start..].to_vec())
    }

    fn draw_initial_state(&mut self) -> InitialState {
        let c = &self.config.initial_state;
        let rng = &mut self.rng;
        let mut symmetric = |half: f64| if half > 0.0 { rng.random_range(-half..=half) } else { 0.0 };
        let offset = Vec3::new(
            symmetric(c.position_offset_m[0]),
            symmetric(c.position_offset_m[1]),
            symmetric(c.position_offset_m[2]),
        );
        let speed = (self.reference.speed(0) + symmetric(c.speed_offset_mps)).max(0.0);
        let attitude = c.attitude_offset_deg.to_radians();
        let (roll, pitch, yaw) = (symmetric(attitude), symmetric(attitude), symmetric(attitude));
        let position_m = self.reference.target(0) + offset;
        if c.path_start_probability > 0.0 && matches!(self.source, ReferenceSource::Procedural) {
            // On the path: along its direction at its speed, turned about the direction of travel so that
            // the lift would bend the path as it bends there (the level start below is this for a level path).
            let along = path_frame(&self.reference);
            return InitialState {
                position_m,
                orientation: along * quat_from_euler(roll, c.pitch_deg.to_radians() + pitch, yaw),
                linear_velocity_mps: self.reference.direction(0) * speed,
                ..InitialState::default()
            };
        }
        let direction = self.reference.direction(0);
        let heading = direction.y.atan2(direction.x);
        InitialState {
            position_m,
            orientation: quat_from_euler(roll, c.pitch_deg.to_radians() + pitch, heading + yaw),
            linear_velocity_mps: Vec3::new(heading.cos(), heading.sin(), 0.0) * speed,
            ..InitialState::default()
        }
    }

    /// Applies `action` for one control step. Does not reset: when `end` is set, call `reset`.
    pub fn step(&mut self, action: &[f32]) -> StepResult {
        let mut targets = self.actions.to_targets(action, &mut self.oscillator);
        let feathering_s = self.config.control.passive_feathering_s;
        if feathering_s > 0.0 {
            // The twist is part of the target applied, and of the previous action the policy observes.
            self.actions.feather(&mut targets, &self.control.sim().joint_velocities(), feathering_s);
        }
        let fault = self.control.step(&targets).err();
        self.step += 1;
        let applied = self.actions.applied(action, &targets);
        let action_change =
            applied.iter().zip(&self.previous_action).map(|(a, b)| f64::from(a - b).powi(2)).sum::<f64>().sqrt();
        self.previous_action = applied;
        let sim = self.control.sim();
        let position = sim.base_position_m();
        let [roll, pitch, _] = quat_to_euler(sim.orientation());
        let error = (self.reference.target(self.step) - position).length();
        let period = self.control.control_period_s();
        let power = self.control.last_step_work().absolute_j / period;
        let time = self.step as f64 * period;
        let flap_rad = sim.joint_positions()[ActuatedJoint::FlapLeft.index()];
        if self.config.reward.flap_rate_weight > 0.0 {
            self.flap_rhythm.update(flap_rad, time, period);
        }
        if self.config.reward.glide_hold_weight > 0.0 {
            self.flap_swing.update(flap_rad);
        }
        if self.config.reward.feathering_weight > 0.0 {
            let (angles, rates) = (sim.joint_positions(), sim.joint_velocities());
            let common =
                |left: ActuatedJoint, right: ActuatedJoint, of: &[f64]| 0.5 * (of[left.index()] + of[right.index()]);
            self.feathering.update(
                common(ActuatedJoint::FlapLeft, ActuatedJoint::FlapRight, &rates),
                common(ActuatedJoint::PitchLeft, ActuatedJoint::PitchRight, &angles),
            );
        }
        let glide_weighed = self.config.reward.glide_hold_weight > 0.0 || self.config.reward.feathering_weight > 0.0;
        let terms = RewardTerms::evaluate(
            &self.config.reward,
            &RewardInputs {
                position_error_m: error,
                body_rate_radps: sim.body_rates().length(),
                roll_rad: roll,
                pitch_rad: pitch,
                absolute_power_w: power,
                action_change,
                flap_hz: self.flap_rhythm.frequency_hz(time),
                flap_swing_deg: self.flap_swing.range_deg(),
                // Read only where r_glide_hold or r_feathering is weighed: it looks along the lookahead for turns.
                glide_share: if glide_weighed { self.glide_share() } else { 0.0 },
                feathering: self.feathering.correlation(),
            },
        )
        .with_position_weighed(self.position_factor())
        .with_energy_priced(self.energy_price_share())
        .with_flap_rate_priced(self.flap_rate_price_share());
        let end = if fault.is_some() {
            Some(EpisodeEnd::SimulationFault)
        } else if let Some(failure) = check_failure(&self.config.episode, error, roll, pitch) {
            Some(failure)
        } else if self.step >= self.time_limit_steps {
            Some(EpisodeEnd::TimeLimit)
        } else if self.step + 1 >= self.reference.steps_with_full_lookahead(self.config.observation.lookahead_steps) {
            Some(EpisodeEnd::ReferenceEnd)
        } else {
            None
        };
        // A broken state earns nothing and is not observed.
        let (reward, terms) =
            if fault.is_some() { (0.0, RewardTerms::default()) } else { (terms.total(&self.config.reward), terms) };
        if fault.is_none() {
            self.observation.push(read_frame(self.control.sim(), &self.previous_action));
        }
        self.episode_return += reward;
        self.term_sums.add(&terms);
        StepResult { reward, position_error_m: error, terms, end }
    }

    /// Truncates the current episode after `steps` steps instead of `episode.max_steps` (at least
    /// one step more than taken so far). Training shortens each environment's first episode by a
    /// different amount so that episodes do not all start and end together.
    pub fn shorten_episode(&mut self, steps: usize) {
        self.time_limit_steps = steps.clamp(self.step + 1, self.config.episode.max_steps);
    }

    /// The episode as it stands, to continue later with [`FlightEnv::restore`].
    pub fn snapshot(&self) -> EnvSnapshot {
        EnvSnapshot {
            rng_at_reset: self.rng_at_reset.clone(),
            control: self.control.state(),
            history: self.observation.history(),
            step: self.step,
            time_limit_steps: self.time_limit_steps,
            previous_action: self.previous_action,
            oscillator: self.oscillator,
            flap_rhythm: self.flap_rhythm,
            flap_swing: self.flap_swing,
            feathering: self.feathering,
            episode_return: self.episode_return,
            term_sums: self.term_sums,
        }
    }

    /// Continues the episode of `snapshot`, taken from an environment with the same model, task and
    /// index: replays its reset, then restores what evolved since.
    pub fn restore(&mut self, snapshot: &EnvSnapshot) -> Result<(), ModelError> {
        let index = self.index;
        let invalid = move |why| ModelError::InvalidValue {
            what: "environment snapshot".into(),
            value: format!("environment {index}"),
            why,
        };
        if snapshot.time_limit_steps > self.config.episode.max_steps || snapshot.step >= snapshot.time_limit_steps {
            return Err(invalid("its episode does not fit this task's time limit"));
        }
        self.rng = snapshot.rng_at_reset.clone();
        self.reset()?;
        self.control.restore(&snapshot.control)?;
        if !self.observation.restore_history(&snapshot.history) {
            return Err(invalid("its observation history does not fit this task's layout"));
        }
        self.step = snapshot.step;
        self.time_limit_steps = snapshot.time_limit_steps;
        self.previous_action = snapshot.previous_action;
        self.oscillator = snapshot.oscillator;
        self.flap_rhythm = snapshot.flap_rhythm;
        self.flap_swing = snapshot.flap_swing;
        self.feathering = snapshot.feathering;
        self.episode_return = snapshot.episode_return;
        self.term_sums = snapshot.term_sums;
        Ok(())
    }

    /// Writes the current observation into `out` (length `observation_layout().size()`).
    pub fn observe(&self, out: &mut [f32]) {
        let sim = self.control.sim();
        self.observation.write(&self.reference, self.step, sim.base_position_m(), sim.orientation(), out);
    }

    /// The share of the energy's price paid at the current step: the speed ramp of
    /// `reward.energy_min_speed_mps` at the reference's speed (1 where that is 0), times exp(-(w /
    /// scale)^2) for the turns ahead where `reward.energy_turn_scale_degps` is set (w as in
    /// [`Self::smoothness_weight`]), times the [`Self::slope_factor`] of `reward.energy_glide_gain` and
    /// `reward.energy_dive_share`.
    pub fn energy_price_share(&self) -> f64 {
        let reward = &self.config.reward;
        let min_speed = reward.energy_min_speed_mps;
        let share = if min_speed > 0.0 { speed_ramp(min_speed, self.reference.speed(self.step)) } else { 1.0 };
        share
            * self.turn_weight(reward.energy_turn_scale_degps)
            * self.slope_factor(reward.energy_glide_gain, reward.energy_dive_share)
    }

    /// r_pos's factor at the current step: 1 + `reward.position_dive_gain` where the reference dives
    /// steeper than a glide slope ([`Self::slope_factor`]), 1 elsewhere (and everywhere at gain 0).
    pub fn position_factor(&self) -> f64 {
        let gain = self.config.reward.position_dive_gain;
        if gain == 0.0 { 1.0 } else { self.slope_factor(0.0, 1.0 + gain) }
    }

    /// The weight of the learner's smoothness term for the action chosen at the current observation:
    /// exp(-(w / scale)^2), w the fastest turn of the reference over the observed lookahead and scale
    /// `reward.smoothness_turn_scale_degps` (1 where that is 0), times the speed ramp of
    /// `reward.smoothness_min_speed_mps` at the reference's current speed (1 where that is 0), times the
    /// [`Self::slope_factor`] of `reward.smoothness_glide_gain` and `reward.smoothness_dive_share`.
    pub fn smoothness_weight(&self) -> f32 {
        let reward = &self.config.reward;
        let mut weight = self.turn_weight(reward.smoothness_turn_scale_degps);
        weight *= speed_ramp(reward.smoothness_min_speed_mps, self.reference.speed(self.step));
        let stop = reward.smoothness_glide_stop_before_dive_s;
        let glide_gain = if stop > 0.0 && self.dives_within_s(stop) { 0.0 } else { reward.smoothness_glide_gain };
        weight *= self.slope_factor(glide_gain, reward.smoothness_dive_share);
        weight as f32
    }

    /// Whether the reference dives steeper than a glide slope at some step of the next `seconds`
    /// (`reward.smoothness_glide_stop_before_dive_s`).
    fn dives_within_s(&self, seconds: f64) -> bool {
        let steps = (seconds / self.reference.dt_s()).round() as usize;
        (self.step + 1..=self.step + steps).any(|k| is_steeper_than_glide(self.reference.velocity(k)))
    }

    /// The share of r_flap_rate's price paid at the current step: `reward.flap_rate_glide_share` on a
    /// glide slope (from 1 on a level path, as [`Self::slope_factor`] rises), 1 elsewhere.
    pub fn flap_rate_price_share(&self) -> f64 {
        let share = self.config.reward.flap_rate_glide_share;
        if share == 1.0 { 1.0 } else { self.slope_factor(share - 1.0, 1.0) }
    }

    /// How much the reference glides at the current step, for r_glide_hold: its sink rate over
    /// [`GLIDE_SINK_MPS`] (at most 1) where it sinks at a slope the robot can glide, 0 on level paths,
    /// climbs and steeper dives; weighed by exp(-(w / scale)^2) for the turns ahead where
    /// `reward.glide_hold_turn_scale_degps` is set (w as in [`Self::smoothness_weight`]).
    pub fn glide_share(&self) -> f64 {
        let share = self.slope_factor(1.0, 1.0) - 1.0;
        if share > 0.0 { share * self.turn_weight(self.config.reward.glide_hold_turn_scale_degps) } else { share }
    }

    /// exp(-(w / scale)^2), w the fastest turn of the reference over the observed lookahead (deg/s):
    /// 1 on a straight path, 1/e where it turns at `scale`; exactly 1 where the scale is 0 (unset), so a
    /// term multiplied by it keeps its bits and the lookahead is not read.
    fn turn_weight(&self, scale_degps: f64) -> f64 {
        if scale_degps <= 0.0 {
            return 1.0;
        }
        let turn = self.reference.fastest_turn_degps(self.step, self.config.observation.lookahead_steps);
        (-(turn / scale_degps).powi(2)).exp()
    }

    /// A reward term's factor for the slope the reference flies at the current step: 1 +
    /// `glide_gain` x its glide share where it sinks at a slope the robot can glide (no steeper than
    /// [`GLIDE_MIN_RATIO`]; the share is the sink rate over [`GLIDE_SINK_MPS`], at most 1), `dive_share`
    /// where it sinks steeper, 1 on level paths and climbs.
    fn slope_factor(&self, glide_gain: f64, dive_share: f64) -> f64 {
        let velocity = self.reference.velocity(self.step);
        let sink = -velocity.z;
        if sink <= 0.0 {
            1.0
        } else if is_steeper_than_glide(velocity) {
            dive_share
        } else {
            1.0 + glide_gain * (sink / GLIDE_SINK_MPS).min(1.0)
        }
    }

    /// The finished episode's summary (call when `step` reported an end, before `reset`).
    pub fn episode_info(&self, end: EpisodeEnd) -> EpisodeInfo {
        EpisodeInfo {
            env_index: self.index,
            episode_return: self.episode_return,
            length: self.step,
            term_sums: self.term_sums,
            end,
        }
    }

    pub fn control(&self) -> &ControlLoop {
        &self.control
    }

    /// The simulator, for tools and tests that need to reach inside (e.g. to inject a fault).
    pub fn sim_mut(&mut self) -> &mut flapper_sim::Simulator {
        self.control.sim_mut()
    }

    pub fn reference(&self) -> &Reference {
        &self.reference
    }

    pub fn step_count(&self) -> usize {
        self.step
    }

    /// The dynamics drawn for this episode.
    pub fn drawn_dynamics(&self) -> &DrawnDynamics {
        &self.drawn
    }

    pub fn config(&self) -> &TaskConfig {
        &self.config
    }
}
