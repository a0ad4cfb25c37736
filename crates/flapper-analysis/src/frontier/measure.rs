//! Flying the trade-off: each controller on longitudinal, cruise and the level 3.0 m/s path from the
//! same randomized starts as `flapper eval` (evaluated with the same library calls), and once from the
//! exact start for the flight modes.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_eval::tracking::{TrackingController, evaluate_tracking};
use flapper_eval::tracking_report::{ANALYSED_JOINTS, TrackingSummary};
use flapper_eval::{PolicyFileError, ScriptedGaitConfig, load_flight_policy};
use flapper_ppo::ActorCritic;
use flapper_sim::{ActuatedJoint, RobotModel};
use flapper_task::TaskConfig;
use flapper_task::reference::Reference;

use super::{CRUISE_REFERENCE, ENERGY_REFERENCE, Frontier, FrontierRow};
use crate::AnalysisError;
use crate::modes::measure_controller_flight_modes;

/// How the trade-off is measured.
#[derive(Debug, Clone)]
pub struct FrontierSettings {
    /// Randomized starts per reference, as `flapper eval --episodes`.
    pub episodes: usize,
    /// Seed of the starts, as `flapper eval --seed`.
    pub seed: u64,
    /// The level 3.0 m/s path ([`super::LEVEL_3_REFERENCE`] where the program runs from elsewhere).
    pub level_reference: PathBuf,
}

/// A trained policy to measure, loaded, with its name.
pub struct FrontierPolicy {
    pub label: String,
    pub path: PathBuf,
    pub policy: Arc<ActorCritic>,
    /// The task it was trained on (what it flies, and how its references are sampled).
    pub task: TaskConfig,
}

impl FrontierPolicy {
    pub fn load(label: impl Into<String>, path: &Path) -> Result<Self, PolicyFileError> {
        let (policy, task) = load_flight_policy(path)?;
        Ok(Self { label: label.into(), path: path.to_owned(), policy: Arc::new(policy), task })
    }
}

/// How many times [`measure_frontier`] calls its progress callback for `policies` policies: four
/// measurements (longitudinal, flight modes, cruise, level 3 m/s) per policy and for the scripted gait.
pub fn step_count(policies: usize) -> usize {
    4 * (policies + 1)
}

/// `j_per_m` over the scripted gait's `scripted_j_per_m`; `None` where either is not a positive number.
pub fn energy_ratio(j_per_m: f64, scripted_j_per_m: f64) -> Option<f64> {
    (scripted_j_per_m > 0.0).then(|| j_per_m / scripted_j_per_m).filter(|ratio| ratio.is_finite())
}

/// What one controller flew.
struct Flown {
    /// The longitudinal reference as it was sampled, and the figures on it.
    longitudinal_reference: Arc<Reference>,
    longitudinal: TrackingSummary,
    /// `None` when the exact-start flight did not complete (the note says so).
    glide_fraction: Option<f64>,
    cruise: TrackingSummary,
    level: TrackingSummary,
}

/// A controller, its name, and the task it flies.
struct Flyer<'a> {
    label: &'a str,
    controller: TrackingController,
    task: &'a TaskConfig,
}

/// Measures every policy and the scripted gait: `progress` is called after each measurement
/// ([`step_count`] in all) with what was done.
pub fn measure_frontier(
    robot: &RobotModel,
    policies: &[FrontierPolicy],
    settings: &FrontierSettings,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Frontier, AnalysisError> {
    let source = format!("flapper frontier --episodes {} --seed {}", settings.episodes, settings.seed);
    let mut notes = Vec::new();
    let scripted_task = TaskConfig::default();
    let scripted = Flyer {
        label: "scripted gait",
        controller: TrackingController::Scripted(ScriptedGaitConfig::default()),
        task: &scripted_task,
    };
    // The scripted gait's longitudinal flights by the sampling of the reference they flew: a policy
    // whose task samples it alike is compared with them, any other flies the scripted gait again.
    let mut scripted_longitudinal: Vec<(Arc<Reference>, f64)> = Vec::new();
    let flown = fly(robot, &scripted, settings, progress, &mut notes)?;
    scripted_longitudinal.push((flown.longitudinal_reference.clone(), flown.longitudinal.energy_per_metre_j));
    let scripted_row = row(&scripted, "", &flown, flown.longitudinal.energy_per_metre_j, &source);

    let mut rows = Vec::new();
    for policy in policies {
        let flyer = Flyer {
            label: &policy.label,
            controller: TrackingController::Policy(policy.policy.clone()),
            task: &policy.task,
        };
        let flown = fly(robot, &flyer, settings, progress, &mut notes)?;
        let reference = &flown.longitudinal_reference;
        let scripted_j_per_m = match scripted_longitudinal.iter().find(|(r, _)| **r == **reference) {
            Some((_, j_per_m)) => *j_per_m,
            None => {
                let summary = track(robot, &scripted, reference, settings)?;
                scripted_longitudinal.push((reference.clone(), summary.energy_per_metre_j));
                summary.energy_per_metre_j
            }
        };
        rows.push(row(&flyer, &policy.path.display().to_string(), &flown, scripted_j_per_m, &source));
    }
    Ok(Frontier { policies: rows, scripted: scripted_row, notes, episodes: settings.episodes, seed: settings.seed })
}

/// `name` (a named reference or a CSV file) sampled as `flapper eval` samples it for a controller
/// trained on `task`.
fn resolve(robot: &RobotModel, task: &TaskConfig, name: &str) -> Result<Arc<Reference>, AnalysisError> {
    let dt_s = task.control_period_s(robot.timestep_s());
    Ok(Arc::new(flapper_task::reference::resolve(name, dt_s, task.observation.lookahead_steps)?))
}

/// `flyer` on `reference` from the settings' randomized starts, summed up as `flapper eval` sums it up.
fn track(
    robot: &RobotModel,
    flyer: &Flyer,
    reference: &Arc<Reference>,
    settings: &FrontierSettings,
) -> Result<TrackingSummary, AnalysisError> {
    let results =
        evaluate_tracking(robot, &flyer.controller, flyer.task, reference.clone(), settings.episodes, settings.seed)?;
    let period_s = flyer.task.control_period_s(robot.timestep_s());
    let window = flapper_task::reference::named::manoeuvre_window_s(reference.name());
    Ok(TrackingSummary::of(&results, period_s, window))
}

/// Everything `flyer` flies, the references sampled for its own task.
fn fly(
    robot: &RobotModel,
    flyer: &Flyer,
    settings: &FrontierSettings,
    progress: &(dyn Fn(&str) + Sync),
    notes: &mut Vec<String>,
) -> Result<Flown, AnalysisError> {
    let label = flyer.label;
    let longitudinal_reference = resolve(robot, flyer.task, ENERGY_REFERENCE)?;
    let longitudinal = track(robot, flyer, &longitudinal_reference, settings)?;
    progress(&format!("{label}: {ENERGY_REFERENCE}"));
    let glide_fraction = match measure_controller_flight_modes(robot, &flyer.controller, flyer.task) {
        Ok(modes) => Some(modes.glide_segment_fraction()),
        Err(AnalysisError::FlightFailed { end, time_s, .. }) => {
            notes.push(format!(
                "{label}: no glide fraction: its flight of {ENERGY_REFERENCE} from the exact start ended '{end}' at {time_s:.1} s"
            ));
            None
        }
        Err(e) => return Err(e),
    };
    progress(&format!("{label}: flight modes"));
    let cruise = track(robot, flyer, &resolve(robot, flyer.task, CRUISE_REFERENCE)?, settings)?;
    progress(&format!("{label}: {CRUISE_REFERENCE}"));
    let level_path = settings.level_reference.display().to_string();
    let level = track(robot, flyer, &resolve(robot, flyer.task, &level_path)?, settings)?;
    progress(&format!("{label}: level 3.0 m/s"));
    Ok(Flown { longitudinal_reference, longitudinal, glide_fraction, cruise, level })
}

fn finite(value: f64) -> Option<f64> {
    value.is_finite().then_some(value)
}

/// The row of what `flyer` flew, its energy against the scripted gait's `scripted_j_per_m`.
fn row(flyer: &Flyer, policy: &str, flown: &Flown, scripted_j_per_m: f64, source: &str) -> FrontierRow {
    let Flown { longitudinal, glide_fraction, cruise, level, .. } = flown;
    let flap = ANALYSED_JOINTS.iter().position(|j| *j == ActuatedJoint::FlapLeft).expect("flap_left is analysed");
    FrontierRow {
        label: flyer.label.to_owned(),
        policy: policy.to_owned(),
        longitudinal_completed: Some(longitudinal.completed),
        longitudinal_episodes: Some(longitudinal.episodes),
        longitudinal_rms_m: finite(longitudinal.mean_rms_error_m),
        longitudinal_j_per_m: finite(longitudinal.energy_per_metre_j),
        scripted_j_per_m: finite(scripted_j_per_m),
        energy_ratio: energy_ratio(longitudinal.energy_per_metre_j, scripted_j_per_m),
        glide_fraction: *glide_fraction,
        cruise_flap_hz: finite(cruise.frequency_hz[flap]),
        level3_completed: Some(level.completed),
        level3_rms_m: finite(level.mean_rms_error_m),
        level3_episodes: Some(level.episodes),
        source: source.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_energy_ratio_of_a_gait_against_itself_is_exactly_one_and_none_without_a_positive_baseline() {
        for j_per_m in [2.4, 2.371_234_567, 1e-9, 13.03] {
            assert_eq!(energy_ratio(j_per_m, j_per_m), Some(1.0), "{j_per_m}");
        }
        assert_eq!(energy_ratio(3.6, 2.4), Some(1.5));
        assert_eq!(energy_ratio(3.6, 0.0), None);
        assert_eq!(energy_ratio(3.6, f64::NAN), None);
        assert_eq!(energy_ratio(f64::NAN, 2.4), None);
    }
}
