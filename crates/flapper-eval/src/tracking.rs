//! Trajectory-tracking evaluation (paper IV-B, IV-C): a controller (a learned policy, or the scripted gait
//! for comparison) flies a fixed reference from randomized starts, episode after episode, and each
//! flight is measured: completion, position error, airspeed, power, energy per metre, and the
//! flapping frequency of flap, wing pitch and tail.

use std::sync::Arc;

use flapper_ppo::{ActorCritic, InferenceScratch};
use flapper_sim::{ActuatedJoint, ModelError, N_ACTUATED_JOINTS, RobotModel, Vec3};
use flapper_task::action::ActionMap;
use flapper_task::config::RandomizationConfig;
use flapper_task::reference::Reference;
use flapper_task::termination::EpisodeEnd;
use flapper_task::{FlightEnv, ReferenceSource, TaskConfig};
use rayon::prelude::*;

use crate::controller::{Controller, FlightState};
use crate::scripted::{ScriptedGait, ScriptedGaitConfig};
use crate::spectrum::{Fundamental, fundamental, phase_lead_deg};

/// Who flies a tracking evaluation: a trained policy, or the scripted gait (the one [`Controller`] that
/// follows a reference). One name for the concept: a controller decides the joint targets; this enum
/// says which one flies the task environment.
#[derive(Debug, Clone)]
pub enum TrackingController {
    /// A trained policy's mean action, normalizer frozen.
    Policy(Arc<ActorCritic>),
    /// The scripted gait, its altitude target following the reference.
    Scripted(ScriptedGaitConfig),
}

/// One control step of an evaluated flight.
#[derive(Debug, Clone, Copy)]
pub struct TrackingStep {
    pub episode: usize,
    pub time_s: f64,
    pub position_m: Vec3,
    pub target_m: Vec3,
    pub error_m: f64,
    pub airspeed_mps: f64,
    pub euler_rad: [f64; 3],
    pub joint_positions_rad: [f64; N_ACTUATED_JOINTS],
    pub joint_velocities_radps: [f64; N_ACTUATED_JOINTS],
    /// PD targets after the 7 Hz filter.
    pub joint_targets_rad: [f64; N_ACTUATED_JOINTS],
    pub mechanical_power_w: f64,
    pub absolute_power_w: f64,
}

/// One evaluated flight.
#[derive(Debug, Clone)]
pub struct EpisodeResult {
    pub end: EpisodeEnd,
    pub steps: Vec<TrackingStep>,
    /// The constant wind the episode flew in (world frame, m/s; zero unless randomized).
    pub wind_mps: Vec3,
}

impl EpisodeResult {
    /// Flew to the end of the reference (no failure, no simulation fault).
    pub fn completed(&self) -> bool {
        matches!(self.end, EpisodeEnd::ReferenceEnd | EpisodeEnd::TimeLimit)
    }

    pub fn rms_error_m(&self) -> f64 {
        (self.steps.iter().map(|s| s.error_m * s.error_m).sum::<f64>() / self.steps.len().max(1) as f64).sqrt()
    }

    pub fn max_error_m(&self) -> f64 {
        self.steps.iter().map(|s| s.error_m).fold(0.0, f64::max)
    }

    /// Flew upside down at some point (|roll| beyond 90 deg).
    pub fn went_inverted(&self) -> bool {
        self.steps.iter().any(|s| s.euler_rad[0].abs() > std::f64::consts::FRAC_PI_2)
    }

    /// Largest position error between `start_s` and `end_s` (NaN if the episode ended before).
    pub fn max_error_between_m(&self, start_s: f64, end_s: f64) -> f64 {
        let inside = self.steps.iter().filter(|s| s.time_s >= start_s && s.time_s <= end_s);
        inside.map(|s| s.error_m).fold(f64::NAN, f64::max)
    }

    /// Seconds after `after_s` until the position error is first within `within_m` (0 if it already
    /// is; `None` if it never is).
    pub fn time_to_rejoin_s(&self, after_s: f64, within_m: f64) -> Option<f64> {
        self.steps.iter().find(|s| s.time_s >= after_s && s.error_m <= within_m).map(|s| (s.time_s - after_s).max(0.0))
    }

    fn mean(&self, f: impl Fn(&TrackingStep) -> f64) -> f64 {
        self.steps.iter().map(f).sum::<f64>() / self.steps.len().max(1) as f64
    }

    pub fn mean_airspeed_mps(&self) -> f64 {
        self.mean(|s| s.airspeed_mps)
    }

    pub fn mean_power_w(&self) -> f64 {
        self.mean(|s| s.mechanical_power_w)
    }

    pub fn mean_absolute_power_w(&self) -> f64 {
        self.mean(|s| s.absolute_power_w)
    }

    /// Absolute mechanical energy over the distance flown.
    pub fn energy_per_metre_j(&self, period_s: f64) -> f64 {
        energy_per_metre_j(&self.steps, period_s)
    }

    /// The fundamental of `joint`'s angle after the first second (the launch transient).
    pub fn fundamental(&self, joint: ActuatedJoint, period_s: f64) -> Option<Fundamental> {
        fundamental(&self.angles_after_launch(joint), 1.0 / period_s)
    }

    /// How far the left wing's pitch leads its flap (deg) at the flap's fundamental, after the first
    /// second: 90 for the scripted gait's feathering (`pitch_lead_deg`). `None` without a stroke.
    pub fn pitch_lead_deg(&self, period_s: f64) -> Option<f64> {
        let flap = self.angles_after_launch(ActuatedJoint::FlapLeft);
        let stroke = fundamental(&flap, 1.0 / period_s)?;
        phase_lead_deg(&flap, &self.angles_after_launch(ActuatedJoint::PitchLeft), stroke.frequency_hz, 1.0 / period_s)
    }

    fn angles_after_launch(&self, joint: ActuatedJoint) -> Vec<f64> {
        self.steps.iter().filter(|s| s.time_s >= 1.0).map(|s| s.joint_positions_rad[joint.index()]).collect()
    }
}

/// Absolute mechanical energy over the distance flown by consecutive control steps `period_s` apart
/// (a whole episode, or a stretch of one).
pub fn energy_per_metre_j<S: std::borrow::Borrow<TrackingStep>>(steps: &[S], period_s: f64) -> f64 {
    let energy: f64 = steps.iter().map(|s| s.borrow().absolute_power_w * period_s).sum();
    let distance: f64 = steps.windows(2).map(|w| (w[1].borrow().position_m - w[0].borrow().position_m).length()).sum();
    energy / distance.max(1e-9)
}

/// The mean over episodes of each one's energy per metre (J/m): `flapper eval`'s figure, and what a
/// curriculum gate's energy bar on a validation entry reads.
pub fn mean_energy_per_metre_j(results: &[EpisodeResult], period_s: f64) -> f64 {
    results.iter().map(|r| r.energy_per_metre_j(period_s)).sum::<f64>() / results.len().max(1) as f64
}

/// The speeds along a path (m/s) the final controller is known to track: its level-flight envelope
/// (`flapper robustness --reference longitudinal`, "envelope": completed in at least 90% of 20
/// episodes of 15 s level flight). A path outside it may still be flown, but nothing vouches for it.
pub const TRACKED_SPEEDS_MPS: [f64; 2] = [3.5, 7.5];

/// A warning for a path that asks for speeds outside [`TRACKED_SPEEDS_MPS`], naming them.
pub fn speed_warning(reference: &Reference) -> Option<String> {
    let [slowest, fastest] = reference.speed_range_mps();
    let [low, high] = TRACKED_SPEEDS_MPS;
    // A hair of tolerance: a path sampled from a 3.5 m/s line is not "outside" by rounding.
    (slowest < low - 0.05 || fastest > high + 0.05).then(|| {
        format!(
            "'{}' asks for {slowest:.1} to {fastest:.1} m/s along the path; the final controller is measured to hold {low}-{high} m/s (docs/evaluation.md), so expect failures outside it",
            reference.name()
        )
    })
}

/// The task as evaluation runs it: `task` (the policy's training task) with randomization off,
/// episodes as long as the reference, and the paper's success criterion alone: an episode fails only
/// by falling more than `max_position_error_m` (3 m) from the target. The attitude rule of stages 1-2
/// never ends an evaluation (roll and pitch are ill-defined near the vertical of a loop); attitude
/// excursions are reported apart.
pub fn evaluation_task(task: &TaskConfig, reference: &Reference) -> TaskConfig {
    let mut config = task.clone();
    config.randomization.enabled = false;
    config.episode.attitude_termination = false;
    config.episode.max_steps = reference.len();
    config
}

/// Flies `episodes` episodes of `reference` with `controller`. Episode k starts from the randomized initial
/// state that environment k of a run seeded `seed` draws (position, speed, attitude offsets).
pub fn evaluate_tracking(
    robot: &RobotModel,
    controller: &TrackingController,
    task: &TaskConfig,
    reference: Arc<Reference>,
    episodes: usize,
    seed: u64,
) -> Result<Vec<EpisodeResult>, ModelError> {
    fly_episodes(robot, controller, evaluation_task(task, &reference), reference, episodes, seed)
}

/// As [`evaluate_tracking`], with the robot's dynamics and the wind drawn per episode from
/// `randomization` (the robustness sweeps). Episode k draws its dynamics, then its start, from
/// environment k's random stream, so its start differs from the unrandomized episode k's.
pub fn evaluate_tracking_randomized(
    robot: &RobotModel,
    controller: &TrackingController,
    task: &TaskConfig,
    randomization: &RandomizationConfig,
    reference: Arc<Reference>,
    episodes: usize,
    seed: u64,
) -> Result<Vec<EpisodeResult>, ModelError> {
    let mut config = evaluation_task(task, &reference);
    config.randomization = randomization.clone();
    fly_episodes(robot, controller, config, reference, episodes, seed)
}

/// The task as `controller` flies it: the scripted gait gives joint targets, whatever actions the
/// policy it is compared with was trained on.
fn controller_task(controller: &TrackingController, mut config: TaskConfig) -> TaskConfig {
    if let TrackingController::Scripted(_) = controller {
        config.control.action_mode = flapper_task::config::ActionMode::JointTargets;
        // The scripted gait shapes its own wing pitch: the yardstick stays the same gait.
        config.control.passive_feathering_s = 0.0;
    }
    config
}

fn fly_episodes(
    robot: &RobotModel,
    controller: &TrackingController,
    config: TaskConfig,
    reference: Arc<Reference>,
    episodes: usize,
    seed: u64,
) -> Result<Vec<EpisodeResult>, ModelError> {
    let config = Arc::new(controller_task(controller, config));
    (0..episodes)
        .into_par_iter()
        .map(|k| {
            let env = FlightEnv::new(robot, config.clone(), ReferenceSource::Fixed(reference.clone()), seed, k)?;
            Ok(fly_episode(env, controller, k, None))
        })
        .collect()
}

/// What the controller saw and did at each control step of one episode: the observation (normalized
/// by nothing: the environment's raw numbers, in `ObservationLayout::names()` order) and the action
/// as the controller gave it (order q1..q5; the environment clips it to [-1, 1]), for checking another
/// implementation against flapper.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EpisodeTrace {
    /// The state the episode started from (after the environment's reset), to fly the same start elsewhere.
    pub start: EpisodeStart,
    pub observations: Vec<Vec<f32>>,
    pub actions: Vec<Vec<f32>>,
}

/// The robot's state at an episode's start, as MuJoCo holds it (`qpos`, `qvel`): every number to the bit.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct EpisodeStart {
    /// The main body's frame in the world (m).
    pub position_m: [f64; 3],
    /// Body to world, MuJoCo's (w, x, y, z) order.
    pub orientation_wxyz: [f64; 4],
    /// World frame (m/s).
    pub velocity_mps: [f64; 3],
    /// Body frame p, q, r (rad/s).
    pub body_rates_radps: [f64; 3],
    /// q1..q5 (rad); the PD targets and the 7 Hz filter start here too.
    pub joint_positions_rad: [f64; N_ACTUATED_JOINTS],
    pub joint_velocities_radps: [f64; N_ACTUATED_JOINTS],
}

impl EpisodeStart {
    fn read(state: &FlightState) -> Self {
        Self {
            position_m: state.position_m.to_array(),
            orientation_wxyz: flapper_sim::quat_to_wxyz(state.orientation),
            velocity_mps: state.velocity_mps.to_array(),
            body_rates_radps: state.body_rates_radps.to_array(),
            joint_positions_rad: state.joint_positions_rad,
            joint_velocities_radps: state.joint_velocities_radps,
        }
    }
}

/// Episode `episode` of an evaluation with `seed` (the same flight as in [`evaluate_tracking`]),
/// with its observations and actions.
pub fn record_episode(
    robot: &RobotModel,
    controller: &TrackingController,
    task: &TaskConfig,
    reference: Arc<Reference>,
    seed: u64,
    episode: usize,
) -> Result<(EpisodeResult, EpisodeTrace), ModelError> {
    let config = Arc::new(controller_task(controller, evaluation_task(task, &reference)));
    let env = FlightEnv::new(robot, config, ReferenceSource::Fixed(reference), seed, episode)?;
    let start = EpisodeStart::read(&FlightState::read(env.control().sim()));
    let mut record = EpisodeTrace { start, ..EpisodeTrace::default() };
    let result = fly_episode(env, controller, episode, Some(&mut record));
    Ok((result, record))
}

/// A controller's state within one episode.
enum ControllerState<'a> {
    Policy { policy: &'a ActorCritic, observation: Vec<f32>, scratch: InferenceScratch },
    Scripted { gait: ScriptedGait, action_map: ActionMap },
}

fn fly_episode(
    mut env: FlightEnv,
    controller: &TrackingController,
    episode: usize,
    mut record: Option<&mut EpisodeTrace>,
) -> EpisodeResult {
    let mut state = match controller {
        TrackingController::Policy(policy) => ControllerState::Policy {
            policy,
            observation: vec![0.0f32; env.observation_layout().size()],
            scratch: InferenceScratch::default(),
        },
        TrackingController::Scripted(config) => ControllerState::Scripted {
            gait: ScriptedGait::new(*config),
            action_map: ActionMap::new(env.control().sim(), &env.config().control, env.control().control_period_s()),
        },
    };
    let mut action = Vec::new();
    let mut steps = Vec::with_capacity(env.reference().len());
    loop {
        match &mut state {
            ControllerState::Policy { policy, observation, scratch } => {
                env.observe(observation);
                policy.act_deterministic(observation, scratch, &mut action);
            }
            ControllerState::Scripted { gait, action_map } => {
                gait.set_altitude_target(env.reference().target(env.step_count()).z);
                let targets = gait.joint_targets(&FlightState::read(env.control().sim()));
                action = action_map.to_action(&targets).to_vec();
            }
        }
        if let Some(record) = record.as_deref_mut() {
            let observation = match &state {
                ControllerState::Policy { observation, .. } => observation.clone(),
                ControllerState::Scripted { .. } => {
                    let mut observation = vec![0.0f32; env.observation_layout().size()];
                    env.observe(&mut observation);
                    observation
                }
            };
            record.observations.push(observation);
            record.actions.push(action.clone());
        }
        let result = env.step(&action);
        let control = env.control();
        let sim = control.sim();
        let state = FlightState::read(sim);
        let target = env.reference().target(env.step_count());
        let work = control.last_step_work();
        steps.push(TrackingStep {
            episode,
            time_s: state.time_s,
            position_m: state.position_m,
            target_m: target,
            error_m: (target - state.position_m).length(),
            airspeed_mps: state.airspeed_mps,
            euler_rad: state.euler_rad,
            joint_positions_rad: state.joint_positions_rad,
            joint_velocities_radps: state.joint_velocities_radps,
            joint_targets_rad: sim.joint_targets(),
            mechanical_power_w: work.net_j / control.control_period_s(),
            absolute_power_w: work.absolute_j / control.control_period_s(),
        });
        if let Some(end) = result.end {
            return EpisodeResult { end, steps, wind_mps: env.drawn_dynamics().wind_mps };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A straight level path along x at `speed_mps`, sampled at 50 Hz for 5 s.
    fn line(speed_mps: f64) -> Reference {
        Reference::new("line.csv", 0.02, (0..250).map(|k| Vec3::new(speed_mps * 0.02 * k as f64, 0.0, 10.0)).collect())
    }

    #[test]
    fn a_path_outside_the_tracked_speeds_is_warned_about_with_its_speeds() {
        assert_eq!(line(4.0).speed_range_mps().map(|v| (v * 1e6).round() / 1e6), [4.0, 4.0]);
        assert!(speed_warning(&line(4.0)).is_none());
        assert!(speed_warning(&line(TRACKED_SPEEDS_MPS[0])).is_none(), "the envelope's edge is inside");
        let slow = speed_warning(&line(2.0)).expect("2 m/s is below the envelope");
        assert!(slow.contains("'line.csv' asks for 2.0 to 2.0 m/s"), "{slow}");
        assert!(speed_warning(&line(9.5)).is_some());
    }
}
