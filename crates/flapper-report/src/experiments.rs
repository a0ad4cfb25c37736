//! The experiments behind the figures, each writing the same files as its own command (`flapper eval`,
//! `sysid`, `phase`, `modes`, `robustness`, `frontier`) into a folder of the report.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_analysis::robustness::{
    PAPER_RANGES, RobustnessSettings, Sweep, default_winds, robustness as run_sweeps, write_robustness,
};
use flapper_eval::tracking::{EpisodeResult, TrackingController, evaluate_tracking};
use flapper_eval::tracking_report::{TrackingSummary, write_tracking_plots};
use flapper_ppo::ActorCritic;
use flapper_sim::RobotModel;
use flapper_task::TaskConfig;
use flapper_task::reference::Reference;

use crate::{FINAL_POLICY, ReportError, ReportSettings, shipped_file, write_json};

/// The named references flown for the tracking figures (Fig. 3, 8, 10, 11) and the comparison.
pub const TRACKED_REFERENCES: [&str; 8] =
    ["cruise", "longitudinal", "lateral", "sharp-turn", "loop", "roll-off-the-bottom", "immelmann", "aerobatic"];

/// `tracking/NAME/summary.json`: what was flown, and the figures `flapper eval` prints.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrackingFile {
    pub reference: String,
    pub duration_s: f64,
    pub episodes: usize,
    pub seed: u64,
    pub policy: String,
    pub summary: TrackingSummary,
}

/// One reference flown from randomized starts.
pub struct Tracked {
    pub name: String,
    pub reference: Arc<Reference>,
    pub results: Vec<EpisodeResult>,
    pub period_s: f64,
}

fn create(dir: &Path) -> Result<(), ReportError> {
    std::fs::create_dir_all(dir).map_err(|e| ReportError::Write { path: dir.to_owned(), message: e.to_string() })
}

/// The reference `name` (a name or a CSV file) sampled at the task's control period, and that period.
fn resolve_reference(robot: &RobotModel, task: &TaskConfig, name: &str) -> Result<(Arc<Reference>, f64), ReportError> {
    let period_s = task.control_period_s(robot.timestep_s());
    let reference = flapper_task::reference::resolve(name, period_s, task.observation.lookahead_steps)
        .map_err(|e| ReportError::step(format!("reference {name}"), e))?;
    Ok((Arc::new(reference), period_s))
}

/// `flapper eval` without the baseline: `summary.json` (the table's figures), plots of 3 episodes.
pub fn tracking(
    robot: &RobotModel,
    controller: &TrackingController,
    task: &TaskConfig,
    name: &str,
    settings: &ReportSettings,
    dir: &Path,
) -> Result<Tracked, ReportError> {
    let (reference, period_s) = resolve_reference(robot, task, name)?;
    let results = evaluate_tracking(robot, controller, task, reference.clone(), settings.episodes, settings.seed)
        .map_err(|e| ReportError::step(format!("tracking on {name}"), e))?;
    let summary = TrackingSummary::of(&results, period_s, flapper_task::reference::named::manoeuvre_window_s(name));
    create(dir)?;
    let file = TrackingFile {
        reference: name.to_owned(),
        duration_s: reference.duration_s(),
        episodes: settings.episodes,
        seed: settings.seed,
        policy: settings.policy.display().to_string(),
        summary,
    };
    write_json(&dir.join("summary.json"), &file)?;
    write_tracking_plots(&results, &format!("policy on {name}"), dir, 3)
        .map_err(|e| ReportError::step(format!("plots of {name}"), e))?;
    Ok(Tracked { name: name.to_owned(), reference, results, period_s })
}

/// `flapper sysid` with `settings`.
pub fn sysid(
    robot: &RobotModel,
    policy: Arc<ActorCritic>,
    task: &TaskConfig,
    settings: &flapper_analysis::sysid::SysidSettings,
    dir: &Path,
) -> Result<(), ReportError> {
    use flapper_analysis::sysid::{fly_records, identify, write_sysid_files};
    let fail = |e: flapper_analysis::AnalysisError| ReportError::step("system identification", e);
    let records = fly_records(robot, policy, task, settings).map_err(fail)?;
    let identified = identify(&records, settings).map_err(fail)?;
    create(dir)?;
    write_sysid_files(dir, &identified, &records).map_err(fail)?;
    Ok(())
}

/// `flapper phase` at the paper's 3 m/s. A policy that cannot fly 3 m/s gets its portraits at the
/// cruise speed of Fig. 3 (3.8 m/s) instead, and the returned note says so and why.
pub fn phase(
    robot: &RobotModel,
    policy: Arc<ActorCritic>,
    task: &TaskConfig,
    dir: &Path,
) -> Result<Option<String>, ReportError> {
    use flapper_analysis::phase::{PAPER_FORWARD_SPEED_MPS, phase_portraits};
    create(dir)?;
    match phase_portraits(robot, policy.clone(), task, PAPER_FORWARD_SPEED_MPS, dir) {
        Ok(_) => Ok(None),
        Err(failed @ flapper_analysis::AnalysisError::FlightFailed { .. }) => {
            phase_portraits(robot, policy, task, flapper_sim::CRUISE_SPEED_MPS, dir)
                .map_err(|e| ReportError::step("phase portraits", e))?;
            Ok(Some(format!(
                "phase portraits at the paper's {PAPER_FORWARD_SPEED_MPS} m/s: {failed}; drawn at {} m/s instead",
                flapper_sim::CRUISE_SPEED_MPS
            )))
        }
        Err(e) => Err(ReportError::step("phase portraits", e)),
    }
}

/// `flapper modes`.
pub fn modes(robot: &RobotModel, policy: Arc<ActorCritic>, task: &TaskConfig, dir: &Path) -> Result<(), ReportError> {
    create(dir)?;
    flapper_analysis::modes::flight_modes(robot, policy, task, dir)
        .map_err(|e| ReportError::step("flight modes", e))?;
    Ok(())
}

/// `flapper robustness` on one reference: the fluid sweep at the paper's ranges, the winds, Table III
/// at once and, with `envelope`, the level airspeed envelope.
pub fn robustness(
    robot: &RobotModel,
    controller: &TrackingController,
    task: &TaskConfig,
    name: &str,
    envelope: bool,
    settings: &ReportSettings,
    dir: &Path,
) -> Result<(), ReportError> {
    let (reference, _) = resolve_reference(robot, task, name)?;
    let mut sweeps = vec![Sweep::Fluid, Sweep::Wind, Sweep::TableIii];
    if envelope {
        sweeps.push(Sweep::Envelope);
    }
    let sweep_settings = RobustnessSettings {
        sweeps,
        episodes: settings.robustness_episodes,
        seed: settings.seed,
        ranges: PAPER_RANGES.to_vec(),
        winds: default_winds(),
    };
    let fail = |e: flapper_analysis::AnalysisError| ReportError::step(format!("robustness on {name}"), e);
    let (report, wind_paths) =
        run_sweeps(robot, controller, task, reference.clone(), &sweep_settings, &|_: &str| {}).map_err(fail)?;
    create(dir)?;
    write_robustness(&report, &wind_paths, &reference, dir).map_err(fail)?;
    Ok(())
}

/// The controllers the energy frontier measures, with their names: the report's own policy (`policy`)
/// by its file where it is not one of the shipped ones below (which it is measured as otherwise), the final
/// controller, every `policies/experiments/NAME/policy.safetensors` (by folder name, in name order), the
/// six-stage final controller before it (`policies/history/six-stages`, which never glides), the previous
/// final controller (`policies/history/previous-final`, trained with the CPU-dependent arithmetic) and the
/// previous stage-4 lineage (`policies/history/stage4`) where they are there.
pub fn frontier_policies(policy: &Path) -> Vec<(String, PathBuf)> {
    let mut shipped = vec![("final".to_owned(), shipped_file(FINAL_POLICY))];
    let mut experiments: Vec<(String, PathBuf)> = std::fs::read_dir(shipped_file(FRONTIER_EXPERIMENTS))
        .into_iter()
        .flatten()
        .flatten()
        .map(|entry| (entry.file_name().to_string_lossy().into_owned(), entry.path().join("policy.safetensors")))
        .filter(|(_, path)| path.is_file())
        .collect();
    experiments.sort();
    shipped.extend(experiments);
    for (label, file) in [
        ("six stages", FRONTIER_SIX_STAGES),
        ("previous final", FRONTIER_PREVIOUS_FINAL),
        ("previous stage-4 lineage", FRONTIER_PREVIOUS_STAGE4),
    ] {
        let path = shipped_file(file);
        if path.is_file() {
            shipped.push((label.to_owned(), path));
        }
    }
    let identity = |path: &Path| path.canonicalize().unwrap_or_else(|_| path.to_owned());
    let own = identity(policy);
    if shipped.iter().any(|(_, path)| identity(path) == own) {
        return shipped;
    }
    let mut policies = vec![(policy.display().to_string(), policy.to_owned())];
    policies.extend(shipped);
    policies
}

/// Where [`frontier_policies`] looks, from the repository's root.
const FRONTIER_EXPERIMENTS: &str = "policies/experiments";
const FRONTIER_SIX_STAGES: &str = "policies/history/six-stages/policy.safetensors";
const FRONTIER_PREVIOUS_FINAL: &str = "policies/history/previous-final/policy.safetensors";
const FRONTIER_PREVIOUS_STAGE4: &str = "policies/history/stage4/policy.safetensors";
/// Points measured in experiments, drawn beside the report's own.
pub const FRONTIER_POINTS: &str = "docs/energy-frontier.csv";

/// `flapper frontier` on [`frontier_policies`] (the report's policy first) with the report's episodes and seed, and
/// [`FRONTIER_POINTS`] as points measured elsewhere: `frontier.csv`, `energy_vs_tracking.svg`.
/// Returns what could not be measured (notes).
pub fn frontier(
    robot: &RobotModel,
    settings: &ReportSettings,
    dir: &Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<String>, ReportError> {
    use flapper_analysis::frontier::file::read_frontier_csv;
    use flapper_analysis::frontier::{FrontierPolicy, FrontierSettings, LEVEL_3_REFERENCE, measure_frontier};
    let fail = |e: &dyn std::fmt::Display| ReportError::step("energy frontier", e);
    let policies = frontier_policies(&settings.policy)
        .into_iter()
        .map(|(label, path)| FrontierPolicy::load(label, &path))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| fail(&e))?;
    let points_file = shipped_file(FRONTIER_POINTS);
    let mut notes = Vec::new();
    let points = if points_file.is_file() {
        read_frontier_csv(&points_file).map_err(|e| fail(&e))?
    } else {
        notes.push(format!("energy frontier without the points measured in experiments: no {FRONTIER_POINTS}"));
        Vec::new()
    };
    let frontier_settings = FrontierSettings {
        episodes: settings.episodes,
        seed: settings.seed,
        level_reference: shipped_file(LEVEL_3_REFERENCE),
    };
    let frontier = measure_frontier(robot, &policies, &frontier_settings, &|done: &str| {
        progress(&format!("energy frontier: {done}"))
    })
    .map_err(|e| fail(&e))?;
    notes.extend(frontier.notes.iter().map(|note| format!("energy frontier: {note}")));
    create(dir)?;
    flapper_analysis::frontier::write_frontier_files(dir, &frontier, &points).map_err(|e| fail(&e))?;
    Ok(notes)
}
