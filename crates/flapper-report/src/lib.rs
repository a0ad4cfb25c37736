//! The report, last in the flow: every experiment behind the paper's figures run with the shipped
//! policies (tracking on the named references, system identification, phase portraits, robustness
//! sweeps, the energy frontier of every shipped controller), rendered snapshots and a flight video, and one page (`index.html`, `report.md`) that
//! shows them beside the paper's numbers ([`paper`]). Every number on the page is read back from the
//! JSON files the run wrote, as the types that wrote them ([`results`]).

pub mod comparison;
mod experiments;
mod page;
pub mod paper;
mod pictures;
pub mod results;
mod tables;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_eval::tracking::TrackingController;
use flapper_sim::RobotModel;

pub use experiments::{TRACKED_REFERENCES, TrackingFile};
pub use tables::{ModelTables, RandomizationUsed, RobotFigures, SurfaceCoefficients, TrainedStage, TrainingTable};

/// What to run. The defaults regenerate the README's report in about 10 minutes on 2 cores.
#[derive(Debug, Clone)]
pub struct ReportSettings {
    /// The controller whose flights, analysis and robustness the report shows (the final one).
    pub policy: PathBuf,
    /// The folder of the curriculum run that trained `policy` (`summary.json`, `stageK/learning_curves.svg`):
    /// the training table and learning curves.
    pub curriculum: PathBuf,
    /// Randomized starts per named reference.
    pub episodes: usize,
    /// Episodes per setting of the robustness sweeps.
    pub robustness_episodes: usize,
    pub seed: u64,
    /// Render the snapshots and the video (needs EGL; the video also ffmpeg).
    pub pictures: bool,
    /// Frame size of the video and of the snapshots (pixels, even numbers).
    pub video_size_px: (usize, usize),
    pub snapshot_size_px: (usize, usize),
    /// The identification experiment (`flapper sysid`'s defaults).
    pub sysid: flapper_analysis::sysid::SysidSettings,
}

impl Default for ReportSettings {
    fn default() -> Self {
        Self {
            policy: shipped_file(FINAL_POLICY),
            curriculum: shipped_file(FINAL_CURRICULUM),
            episodes: 100,
            robustness_episodes: 50,
            seed: 1,
            pictures: true,
            video_size_px: (960, 540),
            snapshot_size_px: (1280, 720),
            sysid: flapper_analysis::sysid::SysidSettings::default(),
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("{0}")]
    Policy(String),
    #[error("{what}: {message}")]
    Step { what: String, message: String },
    #[error("cannot write '{path}': {message}")]
    Write { path: PathBuf, message: String },
    #[error("{0}")]
    Settings(String),
}

impl ReportError {
    fn step(what: impl Into<String>, error: impl std::fmt::Display) -> Self {
        Self::Step { what: what.into(), message: error.to_string() }
    }
}

/// What a report run produced.
#[derive(Debug, Clone)]
pub struct ReportOutcome {
    pub index_html: PathBuf,
    pub report_md: PathBuf,
    /// Parts left out and why (one line each, e.g. no EGL for the pictures).
    pub notes: Vec<String>,
    pub wall_time_s: f64,
}

/// The folders a report writes (beside index.html, report.md and paper_vs_flapper.csv).
const REPORT_PARTS: [&str; 9] =
    ["tracking", "sysid", "phase", "modes", "frontier", "robustness", "render", "training", "tables"];

/// How many times [`generate`] calls its progress callback (for a progress bar).
pub fn step_count(settings: &ReportSettings) -> usize {
    let frontier = flapper_analysis::frontier::step_count(experiments::frontier_policies(&settings.policy).len());
    TRACKED_REFERENCES.len()
        + 3
        + frontier
        + results::ROBUSTNESS_REFERENCES.len()
        + if settings.pictures { 2 } else { 0 }
        + 1
}

/// Runs everything and writes the report into `out` (which must exist). `progress` is called after
/// each step with what was done.
pub fn generate(
    robot: &RobotModel,
    settings: &ReportSettings,
    out: &Path,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<ReportOutcome, ReportError> {
    let began = std::time::Instant::now();
    if settings.episodes == 0
        || settings.episodes > 10_000
        || settings.robustness_episodes == 0
        || settings.robustness_episodes > 10_000
    {
        return Err(ReportError::Settings(format!(
            "episodes must be 1 to 10000 (got {} for tracking and {} for robustness)",
            settings.episodes, settings.robustness_episodes
        )));
    }
    let (policy, task) =
        flapper_eval::load_flight_policy(&settings.policy).map_err(|e| ReportError::Policy(e.to_string()))?;
    let policy = Arc::new(policy);
    // A report folder is regenerated whole: nothing of an earlier run is shown as this one's.
    for part in REPORT_PARTS {
        let dir = out.join(part);
        if dir.exists() {
            std::fs::remove_dir_all(&dir)
                .map_err(|e| ReportError::Write { path: dir.clone(), message: e.to_string() })?;
        }
    }
    let controller = TrackingController::Policy(policy.clone());
    let mut notes = Vec::new();

    let mut tracked = Vec::new();
    for name in TRACKED_REFERENCES {
        tracked.push(experiments::tracking(
            robot,
            &controller,
            &task,
            name,
            settings,
            &out.join("tracking").join(name),
        )?);
        progress(&format!("tracking on {name}"));
    }
    experiments::sysid(robot, policy.clone(), &task, &settings.sysid, &out.join("sysid"))?;
    progress("system identification");
    notes.extend(experiments::phase(robot, policy.clone(), &task, &out.join("phase"))?);
    progress("phase portraits");
    experiments::modes(robot, policy.clone(), &task, &out.join("modes"))?;
    progress("flight modes");
    notes.extend(experiments::frontier(robot, settings, &out.join("frontier"), progress)?);
    // The level-flight envelope does not depend on the reference: the first one measures it for all.
    for (k, name) in results::ROBUSTNESS_REFERENCES.into_iter().enumerate() {
        let envelope = k == 0;
        experiments::robustness(
            robot,
            &controller,
            &task,
            name,
            envelope,
            settings,
            &out.join("robustness").join(name),
        )?;
        progress(&format!("robustness on {name}"));
    }
    let find = |name: &str| tracked.iter().find(|t| t.name == name).expect("every tracked reference is flown");
    pictures::aerobatic_manoeuvres(find("aerobatic"), &out.join("render"))?;
    if settings.pictures {
        let dir = out.join("render");
        match pictures::snapshots(
            robot,
            &[find("loop"), find("sharp-turn"), find("roll-off-the-bottom")],
            settings.snapshot_size_px,
            &dir,
        ) {
            Ok(()) => {}
            Err(e) => notes.push(format!("snapshots not rendered: {e}")),
        }
        progress("snapshots");
        match pictures::video(robot, find("aerobatic"), settings.video_size_px, &dir) {
            Ok(()) => {}
            Err(e) => notes.push(format!("video not made: {e}")),
        }
        progress("video");
    } else {
        notes.push("pictures skipped (--no-pictures)".into());
    }
    tables::training(&settings.curriculum, &out.join("training"))?;
    tables::model_tables(robot, &task, &out.join("tables"))?;
    let results = results::RunResults::read(out);
    let rows = comparison::compare(&results);
    comparison::write_csv(&rows, &out.join("paper_vs_flapper.csv"))?;
    let wall_time_s = began.elapsed().as_secs_f64();
    let page = page::PageInput { out, results: &results, settings, rows: &rows, notes: &notes, wall_time_s };
    let (index_html, report_md) = page::write(&page)?;
    progress("page");
    Ok(ReportOutcome { index_html, report_md, notes, wall_time_s })
}

/// Writes `value` as JSON into `path` ([`flapper_files::write_json`]), creating its folder. The
/// report's own files list their keys in alphabetical order at every level (as `serde_json::Value`
/// holds them), whatever order the type declares.
fn write_json<T: serde::Serialize + ?Sized>(path: &Path, value: &T) -> Result<(), ReportError> {
    create_parent(path)?;
    let fail = |message: String| ReportError::Write { path: path.to_owned(), message };
    let sorted = serde_json::to_value(value).map_err(|e| fail(e.to_string()))?;
    flapper_files::write_json(path, &sorted).map_err(|e| fail(e.to_string()))
}

/// Writes `bytes` to `path` complete or not at all.
fn write_file(path: &Path, bytes: &[u8]) -> Result<(), ReportError> {
    create_parent(path)?;
    flapper_plot::write_atomically(path, bytes)
        .map_err(|e| ReportError::Write { path: path.to_owned(), message: e.to_string() })
}

fn create_parent(path: &Path) -> Result<(), ReportError> {
    match path.parent() {
        Some(dir) => std::fs::create_dir_all(dir)
            .map_err(|e| ReportError::Write { path: dir.to_owned(), message: e.to_string() }),
        None => Ok(()),
    }
}

/// `flapper render`: one flight of `policy` on `reference` (a name or a CSV file) from the randomized
/// start of `seed`, as a chase-camera video (`NAME.mp4`, `NAME_poster.png`) and snapshots overlaid
/// along its manoeuvre, or along the whole flight for a reference without one (`NAME.png`).
/// Returns the files written and, when the video could not be made (no ffmpeg), why.
pub fn render_flight(
    robot: &RobotModel,
    policy: &Path,
    reference: &str,
    seed: u64,
    out: &Path,
) -> Result<(Vec<PathBuf>, Option<String>), ReportError> {
    let (actor, task) = flapper_eval::load_flight_policy(policy).map_err(|e| ReportError::Policy(e.to_string()))?;
    let settings = ReportSettings { policy: policy.to_owned(), episodes: 1, seed, ..ReportSettings::default() };
    let tracked = experiments::tracking(
        robot,
        &TrackingController::Policy(Arc::new(actor)),
        &task,
        reference,
        &settings,
        &out.join("tracking"),
    )?;
    pictures::snapshots(robot, &[&tracked], settings.snapshot_size_px, out)
        .map_err(|e| ReportError::step("rendering", e))?;
    let mut written: Vec<PathBuf> = [
        "robot.png".to_owned(),
        format!("{}.png", pictures::file_stem(&tracked.name)),
        format!("{}_poster.png", pictures::file_stem(&tracked.name)),
    ]
    .iter()
    .map(|f| out.join(f))
    .collect();
    match pictures::video(robot, &tracked, settings.video_size_px, out) {
        Ok(()) => {
            written.push(out.join(format!("{}.mp4", pictures::file_stem(&tracked.name))));
            Ok((written, None))
        }
        Err(flapper_render::RenderError::NoFfmpeg) => {
            Ok((written, Some(flapper_render::RenderError::NoFfmpeg.to_string())))
        }
        Err(e) => Err(ReportError::step("video", e)),
    }
}

/// The final shipped controller, the report's default.
pub const FINAL_POLICY: &str = "policies/final/policy.safetensors";
/// The folder of the curriculum run that trained it.
pub const FINAL_CURRICULUM: &str = "policies/final";

/// A file shipped in the repository (a policy, a config) by its path from the repository's root: found
/// from the current folder, or, when the program runs elsewhere, in the repository it was built from;
/// otherwise the path as given, so that the error names it.
pub fn shipped_file(relative: &str) -> PathBuf {
    let here = PathBuf::from(relative);
    let built_from = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(relative);
    match built_from.canonicalize() {
        Ok(found) if !here.exists() => found,
        _ => here,
    }
}
