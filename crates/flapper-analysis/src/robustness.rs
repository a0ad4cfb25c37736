//! Robustness of a policy (paper IV-D, Fig. 8-9, Table III): how often it still flies a reference when
//! the fluid coefficients are randomized over wider and wider ranges (one at a time and all five
//! together), under constant winds, and with everything in Table III randomized at once; and the
//! level-flight airspeed envelope that explains which winds a reference can be flown in at all.
//!
//! Success is the paper's: the episode reaches the end of the reference without ever being more than
//! 3 m from its target (the evaluation's completion rule). Every setting flies the same number of
//! episodes from randomized starts (environment k of a run seeded `seed`), episodes in parallel.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_eval::tracking::{EpisodeResult, TrackingController, evaluate_tracking, evaluate_tracking_randomized};
use flapper_plot::{COLORS, Curve, Panel};
use flapper_sim::{RobotModel, Vec3};
use flapper_task::TaskConfig;
use flapper_task::config::RandomizationConfig;
use flapper_task::reference::Reference;
use flapper_task::reference::generator::{Piece, build};
use serde::{Deserialize, Serialize};

use crate::AnalysisError;

/// The paper's randomization ranges r (Fig. 9): each coefficient drawn from [1 - r, 1 + r] x nominal.
pub const PAPER_RANGES: [f64; 6] = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5];
/// Widest range accepted (a scale must stay positive).
pub const MAX_RANGE: f64 = 0.9;
/// A level airspeed is sustainable when at least this fraction of its episodes complete.
pub const SUSTAINABLE_SUCCESS: f64 = 0.9;
/// The level-flight references of the envelope: this long (s), at these airspeeds (m/s).
const ENVELOPE_DURATION_S: f64 = 15.0;
const ENVELOPE_SPEEDS_MPS: [f64; 15] = [1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0, 5.5, 6.0, 6.5, 7.0, 7.5, 8.0];
/// Episodes per envelope speed at most (the envelope is a side measurement).
const ENVELOPE_EPISODES: usize = 20;
/// Episodes whose paths are drawn per wind.
const DRAWN_EPISODES: usize = 3;

/// One series of the fluid sweep: a single coefficient randomized, or all five.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FluidSeries {
    Blunt,
    Slender,
    Angular,
    Kutta,
    Magnus,
    All,
}

impl FluidSeries {
    pub const ALL: [FluidSeries; 6] = [Self::Blunt, Self::Slender, Self::Angular, Self::Kutta, Self::Magnus, Self::All];

    /// The name in `robustness_fluid.csv`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Blunt => "blunt",
            Self::Slender => "slender",
            Self::Angular => "angular",
            Self::Kutta => "kutta",
            Self::Magnus => "magnus",
            Self::All => "all",
        }
    }

    /// Which of the five coefficients (MuJoCo's order) the series randomizes.
    pub fn randomized(self) -> [bool; 5] {
        match self {
            Self::All => [true; 5],
            single => std::array::from_fn(|i| i == single as usize),
        }
    }
}

/// Which sweeps to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sweep {
    Fluid,
    Wind,
    TableIii,
    Envelope,
}

impl Sweep {
    pub const ALL: [Sweep; 4] = [Self::Fluid, Self::Wind, Self::TableIii, Self::Envelope];

    pub fn name(self) -> &'static str {
        match self {
            Self::Fluid => "fluid",
            Self::Wind => "wind",
            Self::TableIii => "table3",
            Self::Envelope => "envelope",
        }
    }

    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|s| s.name() == name)
    }
}

/// Randomization switched on with nothing drawn: the nominal robot in still air.
pub fn nominal_randomization() -> RandomizationConfig {
    RandomizationConfig {
        enabled: true,
        episode_fraction: 1.0,
        joint_damping_scale: [1.0, 1.0],
        link_mass_scale: [1.0, 1.0],
        link_inertia_scale: [1.0, 1.0],
        link_com_offset_m: 0.0,
        fluid_coefficient_scale: [1.0, 1.0],
        fluid_coefficients_randomized: [false; 5],
        added_mass_scale: [1.0, 1.0],
        added_inertia_scale: [1.0, 1.0],
        steady_wind_mps: [0.0; 3],
        wind_mps: [0.0; 3],
    }
}

/// The fluid sweep's setting: `series` drawn from [1 - range, 1 + range] x nominal per episode and
/// lifting surface, everything else nominal, no wind.
pub fn fluid_randomization(series: FluidSeries, range: f64) -> RandomizationConfig {
    RandomizationConfig {
        fluid_coefficient_scale: [1.0 - range, 1.0 + range],
        fluid_coefficients_randomized: series.randomized(),
        ..nominal_randomization()
    }
}

/// The wind sweep's setting: the nominal robot in a constant wind (m/s, world frame).
pub fn wind_randomization(wind_mps: [f64; 3]) -> RandomizationConfig {
    RandomizationConfig { steady_wind_mps: wind_mps, ..nominal_randomization() }
}

/// Everything in Table III drawn at once, as stage 4 trains (the task's defaults).
pub fn table_iii_randomization() -> RandomizationConfig {
    RandomizationConfig { enabled: true, ..RandomizationConfig::default() }
}

/// The winds of the sweep (paper Fig. 8): still air; head, tail, cross from either side, up and down
/// at 1 and 2 m/s (relative to the reference's initial heading, +x); the eight corners of Table III's
/// +-2 / +-2 / +-1.5 m/s box.
pub fn default_winds() -> Vec<[f64; 3]> {
    let mut winds = vec![[0.0; 3]];
    for speed in [1.0, 2.0] {
        for direction in
            [[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
        {
            winds.push(direction.map(|d: f64| d * speed));
        }
    }
    for x in [-2.0, 2.0] {
        for y in [-2.0, 2.0] {
            for z in [-1.5, 1.5] {
                winds.push([x, y, z]);
            }
        }
    }
    winds
}

/// A wind's name relative to a reference that starts along +x.
pub fn wind_name(wind: [f64; 3]) -> String {
    let speed = (wind[0] * wind[0] + wind[1] * wind[1] + wind[2] * wind[2]).sqrt();
    let axis = |w: f64, negative: &str, positive: &str| if w < 0.0 { negative.to_owned() } else { positive.to_owned() };
    match wind {
        [0.0, 0.0, 0.0] => "still air".into(),
        [x, 0.0, 0.0] => format!("{} {speed} m/s", axis(x, "head", "tail")),
        [0.0, y, 0.0] => format!("cross from {} {speed} m/s", axis(y, "left", "right")),
        [0.0, 0.0, z] => format!("{} {speed} m/s", axis(z, "down", "up")),
        [x, y, z] => format!("({x}, {y}, {z}) m/s"),
    }
}

/// Successes over one setting's episodes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tally {
    pub episodes: usize,
    pub successes: usize,
    pub success_rate: f64,
    /// Mean RMS position error of the successful episodes (m; NaN when none).
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mean_rms_error_m: f64,
}

impl Tally {
    pub fn of<'a>(results: impl IntoIterator<Item = &'a EpisodeResult>) -> Self {
        let results: Vec<&EpisodeResult> = results.into_iter().collect();
        let completed: Vec<&EpisodeResult> = results.iter().copied().filter(|r| r.completed()).collect();
        let rms = completed.iter().map(|r| r.rms_error_m()).sum::<f64>() / completed.len() as f64;
        Self {
            episodes: results.len(),
            successes: completed.len(),
            success_rate: if results.is_empty() { 0.0 } else { completed.len() as f64 / results.len() as f64 },
            mean_rms_error_m: if completed.is_empty() { f64::NAN } else { rms },
        }
    }
}

/// A row of `robustness_fluid.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FluidRow {
    pub coefficient: String,
    pub range: f64,
    pub episodes: usize,
    pub successes: usize,
    pub success_rate: f64,
}

/// A row of `robustness_wind.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WindRow {
    pub wind_x_mps: f64,
    pub wind_y_mps: f64,
    pub wind_z_mps: f64,
    pub episodes: usize,
    pub successes: usize,
    pub success_rate: f64,
}

/// One fluid setting's result (with the RMS error, which the CSV leaves out).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FluidResult {
    pub coefficient: String,
    pub range: f64,
    #[serde(flatten)]
    pub tally: Tally,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WindResult {
    pub wind_mps: [f64; 3],
    pub name: String,
    #[serde(flatten)]
    pub tally: Tally,
    /// The airspeeds the reference asks for in this wind.
    pub needed_airspeed: NeededAirspeed,
    /// Whether every needed airspeed lies inside the measured level-flight envelope (None when the
    /// envelope sweep did not run or sustained no airspeed).
    pub inside_envelope: Option<bool>,
}

/// The slowest and fastest airspeed (m/s) a reference asks for in a constant wind: the norm of its
/// ground velocity minus the wind, over every step of the path. A wind whose slowest need lies below
/// the robot's slowest sustained level airspeed asks for flight it cannot hold (a tailwind on a slow
/// reference); weaving to shed ground speed would be the only way.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NeededAirspeed {
    pub slowest_mps: f64,
    pub fastest_mps: f64,
}

/// The airspeeds `reference` asks for in the constant `wind_mps` (world frame).
pub fn needed_airspeed(reference: &Reference, wind_mps: [f64; 3]) -> NeededAirspeed {
    let wind = Vec3::from_array(wind_mps);
    let points = reference.points();
    if points.len() < 2 {
        // A path that stands still: hovering in the wind.
        let hover = wind.length();
        return NeededAirspeed { slowest_mps: hover, fastest_mps: hover };
    }
    let airspeeds = points.windows(2).map(|pair| ((pair[1] - pair[0]) / reference.dt_s() - wind).length());
    let (slowest_mps, fastest_mps) = airspeeds.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| (lo.min(v), hi.max(v)));
    NeededAirspeed { slowest_mps, fastest_mps }
}

impl NeededAirspeed {
    /// Whether every needed airspeed lies in the envelope's sustained range (None without one). A
    /// top sustained at the fastest airspeed flown bounds nothing.
    pub fn inside(&self, envelope: &EnvelopeResult) -> Option<bool> {
        match (envelope.slowest_sustained_mps, envelope.fastest_sustained_mps) {
            (Some(lo), Some(hi)) => {
                Some(self.slowest_mps >= lo && (self.fastest_mps <= hi || hi >= envelope.fastest_flown_mps))
            }
            _ => None,
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct EnvelopeResult {
    /// Per level airspeed (m/s): its tally over straight and level flights.
    pub speeds: Vec<(f64, Tally)>,
    /// The slowest and fastest airspeeds at which at least `SUSTAINABLE_SUCCESS` of the episodes
    /// complete (None when none does).
    pub slowest_sustained_mps: Option<f64>,
    pub fastest_sustained_mps: Option<f64>,
    /// The fastest airspeed flown: when it is also the fastest sustained, the envelope's top is not
    /// known, only that it lies above.
    pub fastest_flown_mps: f64,
}

/// `robustness.json`: every setting's figures, and the answers the paper gives.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct RobustnessReport {
    pub reference: String,
    pub episodes: usize,
    pub seed: u64,
    pub fluid: Vec<FluidResult>,
    /// The single coefficient with the lowest success rate at the widest range (the paper: Kutta lift).
    pub most_sensitive_coefficient: Option<String>,
    pub wind: Vec<WindResult>,
    pub table_iii: Option<Tally>,
    /// Table III's episodes whose drawn wind keeps every airspeed the reference asks for inside the
    /// level envelope (the others ask for flight the robot has not shown it can hold); None unless
    /// both the Table III and the envelope sweeps ran and the envelope sustained some airspeed.
    pub table_iii_inside_envelope: Option<Tally>,
    pub envelope: Option<EnvelopeResult>,
    pub wall_time_s: f64,
}

/// What to run.
#[derive(Debug, Clone)]
pub struct RobustnessSettings {
    pub sweeps: Vec<Sweep>,
    pub episodes: usize,
    pub seed: u64,
    pub ranges: Vec<f64>,
    pub winds: Vec<[f64; 3]>,
}

impl RobustnessSettings {
    /// How many settings (each one batch of episodes) the sweeps fly, for a progress bar.
    pub fn settings_count(&self) -> usize {
        self.sweeps
            .iter()
            .map(|sweep| match sweep {
                Sweep::Fluid => FluidSeries::ALL.len() * self.ranges.len(),
                Sweep::Wind => self.winds.len(),
                Sweep::TableIii => 1,
                Sweep::Envelope => ENVELOPE_SPEEDS_MPS.len(),
            })
            .sum()
    }
}

/// A straight and level reference at `speed_mps` for `duration_s` from 10 m up, heading +x.
pub fn level_reference(speed_mps: f64, duration_s: f64, dt_s: f64, lookahead_s: f64) -> Reference {
    let piece = |duration_s| Piece::Command {
        forward_speed_mps: speed_mps,
        vertical_speed_mps: 0.0,
        yaw_rate_radps: 0.0,
        duration_s,
    };
    // As the named references: the lookahead's worth of the same flight after the end.
    let pieces = [piece(duration_s), piece(lookahead_s)];
    build(&format!("level at {speed_mps} m/s"), &pieces, Vec3::new(0.0, 0.0, 10.0), 0.0, dt_s)
}

/// Runs the sweeps of `settings` with `controller` on `reference`; `progress` is called after each
/// setting with its description. Returns the report and, per wind of `report.wind`, its first
/// episodes for the path plots. Writes nothing (see [`write_robustness`]).
pub fn robustness(
    robot: &RobotModel,
    controller: &TrackingController,
    task: &TaskConfig,
    reference: Arc<Reference>,
    settings: &RobustnessSettings,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<(RobustnessReport, Vec<Vec<EpisodeResult>>), AnalysisError> {
    let began = std::time::Instant::now();
    let (episodes, seed) = (settings.episodes, settings.seed);
    let fly = |randomization: &RandomizationConfig| {
        evaluate_tracking_randomized(robot, controller, task, randomization, reference.clone(), episodes, seed)
    };
    let mut report = RobustnessReport {
        reference: reference.name().to_owned(),
        episodes,
        seed,
        fluid: Vec::new(),
        most_sensitive_coefficient: None,
        wind: Vec::new(),
        table_iii: None,
        table_iii_inside_envelope: None,
        envelope: None,
        wall_time_s: 0.0,
    };
    let mut wind_paths = Vec::new();
    let mut table_iii_results = Vec::new();
    for sweep in &settings.sweeps {
        match sweep {
            Sweep::Fluid => {
                for series in FluidSeries::ALL {
                    for &range in &settings.ranges {
                        let tally = Tally::of(&fly(&fluid_randomization(series, range))?);
                        progress(&format!(
                            "{} x[{:.1}, {:.1}]: {}/{}",
                            series.name(),
                            1.0 - range,
                            1.0 + range,
                            tally.successes,
                            tally.episodes
                        ));
                        report.fluid.push(FluidResult { coefficient: series.name().to_owned(), range, tally });
                    }
                }
                report.most_sensitive_coefficient = most_sensitive(&report.fluid);
            }
            Sweep::Wind => {
                for &wind in &settings.winds {
                    let mut results = fly(&wind_randomization(wind))?;
                    let tally = Tally::of(&results);
                    progress(&format!("wind {}: {}/{}", wind_name(wind), tally.successes, tally.episodes));
                    let needed_airspeed = needed_airspeed(&reference, wind);
                    report.wind.push(WindResult {
                        wind_mps: wind,
                        name: wind_name(wind),
                        tally,
                        needed_airspeed,
                        inside_envelope: None,
                    });
                    results.truncate(DRAWN_EPISODES);
                    wind_paths.push(results);
                }
            }
            Sweep::TableIii => {
                table_iii_results = fly(&table_iii_randomization())?;
                let tally = Tally::of(&table_iii_results);
                progress(&format!("Table III: {}/{}", tally.successes, tally.episodes));
                report.table_iii = Some(tally);
            }
            Sweep::Envelope => {
                let lookahead_s = task.observation.lookahead_steps as f64 * reference.dt_s();
                let mut speeds = Vec::new();
                for speed in ENVELOPE_SPEEDS_MPS {
                    let level = Arc::new(level_reference(speed, ENVELOPE_DURATION_S, reference.dt_s(), lookahead_s));
                    let tally = Tally::of(&evaluate_tracking(
                        robot,
                        controller,
                        task,
                        level,
                        episodes.min(ENVELOPE_EPISODES),
                        seed,
                    )?);
                    progress(&format!("level at {speed} m/s: {}/{}", tally.successes, tally.episodes));
                    speeds.push((speed, tally));
                }
                let sustained: Vec<f64> =
                    speeds.iter().filter(|(_, t)| t.success_rate >= SUSTAINABLE_SUCCESS).map(|(v, _)| *v).collect();
                report.envelope = Some(EnvelopeResult {
                    slowest_sustained_mps: sustained.first().copied(),
                    fastest_sustained_mps: sustained.last().copied(),
                    fastest_flown_mps: ENVELOPE_SPEEDS_MPS[ENVELOPE_SPEEDS_MPS.len() - 1],
                    speeds,
                });
            }
        }
    }
    if let Some(envelope) = &report.envelope {
        for wind in &mut report.wind {
            wind.inside_envelope = wind.needed_airspeed.inside(envelope);
        }
        if report.table_iii.is_some() && envelope.slowest_sustained_mps.is_some() {
            let inside = |result: &&EpisodeResult| {
                needed_airspeed(&reference, result.wind_mps.to_array()).inside(envelope) == Some(true)
            };
            report.table_iii_inside_envelope = Some(Tally::of(table_iii_results.iter().filter(inside)));
        }
    }
    report.wall_time_s = began.elapsed().as_secs_f64();
    Ok((report, wind_paths))
}

/// The single coefficient with the lowest success rate at the widest range flown.
fn most_sensitive(fluid: &[FluidResult]) -> Option<String> {
    let widest = fluid.iter().map(|f| f.range).fold(f64::NEG_INFINITY, f64::max);
    fluid
        .iter()
        .filter(|f| f.range == widest && f.coefficient != FluidSeries::All.name() && widest > 0.0)
        .min_by(|a, b| a.tally.success_rate.total_cmp(&b.tally.success_rate))
        .map(|f| f.coefficient.clone())
}

/// Writes `robustness.json`, `robustness_fluid.csv` and `robustness_fluid.svg` (when the fluid sweep
/// ran), `robustness_wind.csv` and `robustness_wind.svg` (when the wind sweep ran); returns the paths.
pub fn write_robustness(
    report: &RobustnessReport,
    wind_paths: &[Vec<EpisodeResult>],
    reference: &Reference,
    dir: &Path,
) -> Result<Vec<PathBuf>, AnalysisError> {
    let fail =
        |path: &Path, e: &dyn std::fmt::Display| AnalysisError::Write { path: path.to_owned(), message: e.to_string() };
    let mut written = Vec::new();
    let json = dir.join("robustness.json");
    flapper_files::write_json(&json, report).map_err(|e| fail(&json, &e))?;
    written.push(json);
    if !report.fluid.is_empty() {
        let path = dir.join("robustness_fluid.csv");
        let rows = report.fluid.iter().map(|f| FluidRow {
            coefficient: f.coefficient.to_owned(),
            range: f.range,
            episodes: f.tally.episodes,
            successes: f.tally.successes,
            success_rate: f.tally.success_rate,
        });
        flapper_files::write_csv_records(&path, rows).map_err(|e| fail(&path, &e))?;
        written.push(path);
        let svg = dir.join("robustness_fluid.svg");
        draw_fluid(report, &svg).map_err(|e| fail(&svg, &e))?;
        written.push(svg);
    }
    if !report.wind.is_empty() {
        let path = dir.join("robustness_wind.csv");
        let rows = report.wind.iter().map(|w| WindRow {
            wind_x_mps: w.wind_mps[0],
            wind_y_mps: w.wind_mps[1],
            wind_z_mps: w.wind_mps[2],
            episodes: w.tally.episodes,
            successes: w.tally.successes,
            success_rate: w.tally.success_rate,
        });
        flapper_files::write_csv_records(&path, rows).map_err(|e| fail(&path, &e))?;
        written.push(path);
        let svg = dir.join("robustness_wind.svg");
        draw_wind_paths(&report.wind, wind_paths, reference, &svg).map_err(|e| fail(&svg, &e))?;
        written.push(svg);
    }
    Ok(written)
}

/// Fig. 9: success rate (%) against the randomization range, one curve per series.
fn draw_fluid(report: &RobustnessReport, path: &Path) -> Result<(), String> {
    let colors = [COLORS[0], COLORS[1], COLORS[2], COLORS[3], COLORS[4], flapper_plot::RGBColor(0, 0, 0)];
    let curves = FluidSeries::ALL
        .iter()
        .zip(colors)
        .map(|(series, color)| Curve {
            label: series.name().to_owned(),
            points: report
                .fluid
                .iter()
                .filter(|f| f.coefficient == series.name())
                .map(|f| (f.range, 100.0 * f.tally.success_rate))
                .collect(),
            color,
            dashed: *series == FluidSeries::All,
        })
        .collect();
    let panel = Panel {
        title: format!(
            "{}: success over {} episodes per point, coefficients x[1 - r, 1 + r]",
            report.reference, report.episodes
        ),
        x_label: "randomization range r",
        y_label: "success rate (%)",
        curves,
        equal_aspect: false,
    };
    flapper_plot::draw(path, (900, 600), &[panel], (1, 1))
}

/// Fig. 8: top and side views of the first episodes under each 2 m/s axis wind (and still air), the
/// reference dashed and the wind drawn as an arrow from the start (1 m per m/s).
fn draw_wind_paths(
    winds: &[WindResult],
    wind_paths: &[Vec<EpisodeResult>],
    reference: &Reference,
    path: &Path,
) -> Result<(), String> {
    let shown: Vec<(&WindResult, &Vec<EpisodeResult>)> = winds
        .iter()
        .zip(wind_paths)
        .filter(|(w, _)| {
            let nonzero = w.wind_mps.iter().filter(|c| **c != 0.0).count();
            nonzero == 0 || (nonzero == 1 && w.wind_mps.iter().any(|c| c.abs() == 2.0))
        })
        .collect();
    let shown = if shown.is_empty() { winds.iter().zip(wind_paths).take(6).collect() } else { shown };
    let reference_points = reference.points();
    let start = reference_points[0];
    let mut panels = Vec::new();
    for (wind, results) in &shown {
        for (view, (a, b)) in [("top", (0usize, 1usize)), ("side", (0, 2))] {
            let pick = |p: Vec3| {
                let c = [p.x, p.y, p.z];
                (c[a], c[b])
            };
            let mut curves = vec![Curve {
                label: "reference".into(),
                points: reference_points.iter().map(|p| pick(*p)).collect(),
                color: COLORS[4],
                dashed: true,
            }];
            for (k, result) in results.iter().enumerate() {
                curves.push(Curve {
                    label: format!(
                        "episode {k} ({})",
                        if result.completed() { "completed" } else { result.end.name() }
                    ),
                    points: result.steps.iter().map(|s| pick(s.position_m)).collect(),
                    color: COLORS[k % 4],
                    dashed: false,
                });
            }
            let wind_vector = Vec3::new(wind.wind_mps[0], wind.wind_mps[1], wind.wind_mps[2]);
            if wind_vector.length() > 0.0 {
                let tip = start + wind_vector;
                let (tx, ty) = pick(tip);
                let (sx, sy) = pick(start);
                // The arrow: a shaft and two barbs a quarter of its length.
                let (dx, dy) = (tx - sx, ty - sy);
                let barb = |sign: f64| (tx - 0.25 * (dx - sign * dy), ty - 0.25 * (dy + sign * dx));
                let points = vec![(sx, sy), (tx, ty), barb(1.0), (tx, ty), barb(-1.0)];
                curves.push(Curve {
                    label: "wind (1 m per m/s)".into(),
                    points,
                    color: flapper_plot::RGBColor(0, 0, 0),
                    dashed: false,
                });
            }
            panels.push(Panel {
                title: format!(
                    "{}, {view} view: {}/{} completed; needs {:.1}-{:.1} m/s airspeed",
                    wind.name,
                    wind.tally.successes,
                    wind.tally.episodes,
                    wind.needed_airspeed.slowest_mps,
                    wind.needed_airspeed.fastest_mps
                ),
                x_label: "x (m)",
                y_label: if b == 1 { "y (m)" } else { "z (m)" },
                curves,
                equal_aspect: true,
            });
        }
    }
    let rows = shown.len().max(1);
    flapper_plot::draw(path, (1200, 420 * rows as u32), &panels, (rows, 2))
}
