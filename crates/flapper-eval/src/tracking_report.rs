//! What an evaluation prints and writes: the summary table's figures (with the manoeuvre's, where the
//! reference has one), the per-step CSV, and the plots (path against reference in 3-D, top and side
//! views; position error against time; joint angles and targets over one second, as the paper's
//! Fig. 3; altitude, airspeed, roll and pitch against time).

use std::path::{Path, PathBuf};

use flapper_files::decimals::{each_fixed, fixed};
use flapper_files::write_csv_rows;
use flapper_plot::{COLORS, Curve, Panel};
use flapper_sim::{ActuatedJoint, N_ACTUATED_JOINTS};

use crate::OutputError;
use crate::plots::{JointSample, write_joint_window};
use crate::tracking::{EpisodeResult, EpisodeTrace, TrackingStep};

/// The joints whose flapping frequency is reported (the paper's flap, wing pitch and tail).
pub const ANALYSED_JOINTS: [ActuatedJoint; 3] =
    [ActuatedJoint::FlapLeft, ActuatedJoint::PitchLeft, ActuatedJoint::TailPitch];

/// Figures over all episodes of one controller on one reference.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TrackingSummary {
    pub episodes: usize,
    pub completed: usize,
    /// Episodes that did not complete, by how they ended (termination reason name, count).
    pub failures: Vec<(String, usize)>,
    /// Mean over episodes of each episode's RMS position error.
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mean_rms_error_m: f64,
    /// Worst RMS error of any episode.
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub worst_rms_error_m: f64,
    /// Largest position error at any step of any episode.
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub max_error_m: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mean_airspeed_mps: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mean_power_w: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mean_absolute_power_w: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub energy_per_metre_j: f64,
    /// Mean fundamental frequency and energy fraction of [`ANALYSED_JOINTS`] over the episodes
    /// (NaN where a joint does not move).
    #[serde(deserialize_with = "flapper_files::nan_as_null::numbers")]
    pub frequency_hz: [f64; 3],
    #[serde(deserialize_with = "flapper_files::nan_as_null::numbers")]
    pub energy_fraction: [f64; 3],
    /// How far the left wing's pitch leads its flap (deg) at the flap's fundamental, the circular mean
    /// over the episodes with a stroke: 90 is the scripted gait's feathering (NaN without a stroke, and
    /// in summaries written before it).
    #[serde(default = "not_measured", deserialize_with = "flapper_files::nan_as_null::number")]
    pub pitch_lead_deg: f64,
    /// Episodes that flew upside down at some point (|roll| beyond 90 deg): expected in loops,
    /// reported because evaluation never ends an episode on attitude.
    pub inverted_episodes: usize,
    /// How the manoeuvre went, for references that have one.
    pub manoeuvre: Option<ManoeuvreFigures>,
}

/// Tracking through a reference's manoeuvre (its window from `manoeuvre_window_s`), over the episodes
/// that flew through it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ManoeuvreFigures {
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub start_s: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub end_s: f64,
    /// Episodes that were still flying at the manoeuvre's end.
    pub episodes: usize,
    /// Largest position error during the manoeuvre: mean over episodes and worst.
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mean_max_error_m: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub worst_max_error_m: f64,
    /// Time after the manoeuvre until within [`REJOIN_DISTANCE_M`] of the target: median and worst
    /// over the episodes that rejoined, and how many never did.
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub median_rejoin_s: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub worst_rejoin_s: f64,
    pub never_rejoined: usize,
}

/// "Back on the path" after a manoeuvre.
pub const REJOIN_DISTANCE_M: f64 = 0.5;

impl ManoeuvreFigures {
    pub fn of(results: &[EpisodeResult], (start_s, end_s): (f64, f64)) -> Self {
        let through: Vec<&EpisodeResult> =
            results.iter().filter(|r| r.steps.last().is_some_and(|s| s.time_s >= end_s)).collect();
        let max_errors: Vec<f64> = through.iter().map(|r| r.max_error_between_m(start_s, end_s)).collect();
        let mut rejoin: Vec<f64> =
            through.iter().filter_map(|r| r.time_to_rejoin_s(end_s, REJOIN_DISTANCE_M)).collect();
        rejoin.sort_by(f64::total_cmp);
        let n = max_errors.len();
        Self {
            start_s,
            end_s,
            episodes: n,
            mean_max_error_m: if n == 0 { f64::NAN } else { max_errors.iter().sum::<f64>() / n as f64 },
            worst_max_error_m: max_errors.iter().copied().fold(f64::NAN, f64::max),
            median_rejoin_s: rejoin.get(rejoin.len() / 2).copied().unwrap_or(f64::NAN),
            worst_rejoin_s: rejoin.last().copied().unwrap_or(f64::NAN),
            never_rejoined: n - rejoin.len(),
        }
    }
}

fn not_measured() -> f64 {
    f64::NAN
}

/// The circular mean (deg) of angles in degrees; NaN for none.
fn circular_mean_deg(angles_deg: &[f64]) -> f64 {
    if angles_deg.is_empty() {
        return f64::NAN;
    }
    let (sin, cos) =
        angles_deg.iter().fold((0.0, 0.0), |(s, c), a| (s + a.to_radians().sin(), c + a.to_radians().cos()));
    sin.atan2(cos).to_degrees()
}

impl TrackingSummary {
    /// Figures of `results`; `manoeuvre_window_s` (start, end) adds the manoeuvre's figures.
    pub fn of(results: &[EpisodeResult], period_s: f64, manoeuvre_window_s: Option<(f64, f64)>) -> Self {
        let n = results.len().max(1) as f64;
        let mean = |f: &dyn Fn(&EpisodeResult) -> f64| results.iter().map(f).sum::<f64>() / n;
        let mut frequency_hz = [f64::NAN; 3];
        let mut energy_fraction = [f64::NAN; 3];
        for (k, joint) in ANALYSED_JOINTS.iter().enumerate() {
            let found: Vec<_> = results.iter().filter_map(|r| r.fundamental(*joint, period_s)).collect();
            if !found.is_empty() {
                frequency_hz[k] = found.iter().map(|f| f.frequency_hz).sum::<f64>() / found.len() as f64;
                energy_fraction[k] = found.iter().map(|f| f.energy_fraction).sum::<f64>() / found.len() as f64;
            }
        }
        let failures = flapper_task::termination::EpisodeEnd::ALL
            .iter()
            .map(|end| (end.name().to_owned(), results.iter().filter(|r| !r.completed() && r.end == *end).count()))
            .filter(|(_, n)| *n > 0)
            .collect();
        Self {
            episodes: results.len(),
            completed: results.iter().filter(|r| r.completed()).count(),
            failures,
            mean_rms_error_m: mean(&|r| r.rms_error_m()),
            worst_rms_error_m: results.iter().map(|r| r.rms_error_m()).fold(0.0, f64::max),
            max_error_m: results.iter().map(|r| r.max_error_m()).fold(0.0, f64::max),
            mean_airspeed_mps: mean(&|r| r.mean_airspeed_mps()),
            mean_power_w: mean(&|r| r.mean_power_w()),
            mean_absolute_power_w: mean(&|r| r.mean_absolute_power_w()),
            energy_per_metre_j: crate::tracking::mean_energy_per_metre_j(results, period_s),
            frequency_hz,
            energy_fraction,
            pitch_lead_deg: circular_mean_deg(
                &results.iter().filter_map(|r| r.pitch_lead_deg(period_s)).collect::<Vec<_>>(),
            ),
            inverted_episodes: results.iter().filter(|r| r.went_inverted()).count(),
            manoeuvre: manoeuvre_window_s.map(|window| ManoeuvreFigures::of(results, window)),
        }
    }

    /// The table's rows: (label, formatted value).
    pub fn rows(&self) -> Vec<(String, String)> {
        let mut rows = vec![
            ("completed".to_string(), format!("{}/{}", self.completed, self.episodes)),
            (
                "ended early".into(),
                if self.failures.is_empty() {
                    "-".into()
                } else {
                    self.failures.iter().map(|(name, n)| format!("{name} {n}")).collect::<Vec<_>>().join(", ")
                },
            ),
            ("RMS position error (m), mean".into(), format!("{:.3}", self.mean_rms_error_m)),
            ("RMS position error (m), worst".into(), format!("{:.3}", self.worst_rms_error_m)),
            ("max position error (m)".into(), format!("{:.3}", self.max_error_m)),
            ("mean airspeed (m/s)".into(), format!("{:.2}", self.mean_airspeed_mps)),
            ("mechanical power (W), net".into(), format!("{:.2}", self.mean_power_w)),
            ("mechanical power (W), absolute".into(), format!("{:.2}", self.mean_absolute_power_w)),
            ("energy per metre (J/m)".into(), format!("{:.2}", self.energy_per_metre_j)),
            ("episodes inverted (|roll| > 90 deg)".into(), format!("{}/{}", self.inverted_episodes, self.episodes)),
        ];
        if let Some(m) = &self.manoeuvre {
            rows.push((
                format!("manoeuvre {:.1}-{:.1} s: flown through", m.start_s, m.end_s),
                format!("{}/{}", m.episodes, self.episodes),
            ));
            let pair = |a: f64, b: f64| if a.is_nan() { "-".to_string() } else { format!("{a:.2} / {b:.2}") };
            rows.push(("  max error in it (m), mean / worst".into(), pair(m.mean_max_error_m, m.worst_max_error_m)));
            rows.push((
                format!("  back within {REJOIN_DISTANCE_M} m after (s), median / worst"),
                pair(m.median_rejoin_s, m.worst_rejoin_s),
            ));
            rows.push(("  never back within it".into(), m.never_rejoined.to_string()));
        }
        for (k, joint) in ANALYSED_JOINTS.iter().enumerate() {
            rows.push((
                format!("{} fundamental (Hz, energy)", joint.name()),
                format!("{:.2} Hz, {:.0}%", self.frequency_hz[k], 100.0 * self.energy_fraction[k]),
            ));
        }
        rows.push(("wing pitch leads the flap (deg)".into(), format!("{:.0}", self.pitch_lead_deg)));
        rows
    }
}

/// A row of `steps.csv`: one control step of one episode (columns in [`steps_csv_header`]'s order).
#[derive(serde::Serialize)]
struct StepRow {
    episode: usize,
    #[serde(serialize_with = "fixed::<2, _>")]
    time_s: f64,
    #[serde(serialize_with = "each_fixed::<4, _>")]
    position_m: [f64; 3],
    #[serde(serialize_with = "each_fixed::<4, _>")]
    target_m: [f64; 3],
    #[serde(serialize_with = "fixed::<4, _>")]
    error_m: f64,
    #[serde(serialize_with = "fixed::<3, _>")]
    airspeed_mps: f64,
    #[serde(serialize_with = "each_fixed::<4, _>")]
    euler_rad: [f64; 3],
    /// Each joint's angle, then its target.
    #[serde(serialize_with = "each_fixed::<4, _>")]
    joints_rad: [f64; 2 * N_ACTUATED_JOINTS],
    #[serde(serialize_with = "fixed::<3, _>")]
    mechanical_power_w: f64,
    #[serde(serialize_with = "fixed::<3, _>")]
    absolute_power_w: f64,
}

impl StepRow {
    fn of(s: &TrackingStep) -> Self {
        let mut joints_rad = [0.0; 2 * N_ACTUATED_JOINTS];
        for (i, pair) in joints_rad.chunks_exact_mut(2).enumerate() {
            pair.copy_from_slice(&[s.joint_positions_rad[i], s.joint_targets_rad[i]]);
        }
        Self {
            episode: s.episode,
            time_s: s.time_s,
            position_m: s.position_m.to_array(),
            target_m: s.target_m.to_array(),
            error_m: s.error_m,
            airspeed_mps: s.airspeed_mps,
            euler_rad: s.euler_rad,
            joints_rad,
            mechanical_power_w: s.mechanical_power_w,
            absolute_power_w: s.absolute_power_w,
        }
    }
}

/// The column names of [`StepRow`].
fn steps_csv_header() -> Vec<String> {
    let mut header: Vec<String> = [
        "episode",
        "time_s",
        "x_m",
        "y_m",
        "z_m",
        "target_x_m",
        "target_y_m",
        "target_z_m",
        "error_m",
        "airspeed_mps",
        "roll_rad",
        "pitch_rad",
        "yaw_rad",
    ]
    .map(String::from)
    .to_vec();
    for joint in ActuatedJoint::ALL {
        header.push(format!("{}_rad", joint.name()));
        header.push(format!("{}_target_rad", joint.name()));
    }
    header.extend(["mechanical_power_w".into(), "absolute_power_w".into()]);
    header
}

/// One row per control step of every episode.
pub fn write_steps_csv(results: &[EpisodeResult], path: &Path) -> Result<(), OutputError> {
    let rows = results.iter().flat_map(|r| &r.steps).map(StepRow::of);
    write_csv_rows(path, &steps_csv_header(), rows)
        .map_err(|e| OutputError::Write { path: path.to_owned(), message: e.to_string() })
}

/// Writes `path_3d.svg`, `path.svg` (top and side views), `error.svg` and `joints.svg` for the first
/// `shown` episodes of `results` into `dir`; returns their paths.
pub fn write_tracking_plots(
    results: &[EpisodeResult],
    title: &str,
    dir: &Path,
    shown: usize,
) -> Result<Vec<PathBuf>, OutputError> {
    let draw = |path: &Path, size, panels: &[Panel], grid| {
        flapper_plot::draw(path, size, panels, grid)
            .map_err(|message| OutputError::Write { path: path.to_owned(), message })
    };
    let shown: Vec<&EpisodeResult> = results.iter().take(shown.max(1)).collect();
    let Some(first) = shown.first() else { return Ok(Vec::new()) };
    let curve = |label: String, points: Vec<(f64, f64)>, k: usize, dashed| Curve {
        label,
        points,
        color: COLORS[k % COLORS.len()],
        dashed,
    };
    let view = |name: &str, pick: fn(&flapper_sim::Vec3) -> (f64, f64), y_label| {
        let mut curves =
            vec![curve("reference".into(), first.steps.iter().map(|s| pick(&s.target_m)).collect(), 0, true)];
        for (k, r) in shown.iter().enumerate() {
            curves.push(curve(
                format!("episode {}", k),
                r.steps.iter().map(|s| pick(&s.position_m)).collect(),
                k + 1,
                false,
            ));
        }
        Panel { title: format!("{title}: {name}"), x_label: "x (m)", y_label, curves, equal_aspect: true }
    };
    let path_views = dir.join("path.svg");
    draw(
        &path_views,
        (1100, 900),
        &[view("top view", |p| (p.x, p.y), "y (m)"), view("side view", |p| (p.x, p.z), "z (m)")],
        (2, 1),
    )?;

    let path_3d = dir.join("path_3d.svg");
    let reference: Vec<(f64, f64, f64)> =
        first.steps.iter().map(|s| (s.target_m.x, s.target_m.y, s.target_m.z)).collect();
    let flown: Vec<Vec<(f64, f64, f64)>> = shown
        .iter()
        .map(|r| r.steps.iter().map(|s| (s.position_m.x, s.position_m.y, s.position_m.z)).collect())
        .collect();
    flapper_plot::draw_paths_3d(&path_3d, &format!("{title}: path (dashed: reference)"), &reference, &flown)
        .map_err(|message| OutputError::Write { path: path_3d.clone(), message })?;

    let error = dir.join("error.svg");
    let curves = shown
        .iter()
        .enumerate()
        .map(|(k, r)| curve(format!("episode {k}"), r.steps.iter().map(|s| (s.time_s, s.error_m)).collect(), k, false))
        .collect();
    draw(
        &error,
        (1000, 450),
        &[Panel {
            title: format!("{title}: position error"),
            x_label: "time (s)",
            y_label: "error (m)",
            curves,
            equal_aspect: false,
        }],
        (1, 1),
    )?;

    // One second in the middle of the first episode (the paper's Fig. 3).
    let t_mid = first.steps.last().map_or(0.0, |s| s.time_s) / 2.0;
    let window: Vec<JointSample> = first
        .steps
        .iter()
        .filter(|s| s.time_s >= t_mid && s.time_s < t_mid + 1.0)
        .map(|s| JointSample { time_s: s.time_s, angles_rad: s.joint_positions_rad, targets_rad: s.joint_targets_rad })
        .collect();
    let joints = dir.join("joints.svg");
    write_joint_window(&window, "one second of episode 0", &joints)?;

    let attitude = dir.join("attitude.svg");
    let over_time =
        |name: &str, y_label, value: fn(&TrackingStep) -> f64, with_reference: Option<fn(&TrackingStep) -> f64>| {
            let mut curves: Vec<Curve> = shown
                .iter()
                .enumerate()
                .map(|(k, r)| {
                    curve(format!("episode {k}"), r.steps.iter().map(|s| (s.time_s, value(s))).collect(), k + 1, false)
                })
                .collect();
            if let Some(target) = with_reference {
                curves.insert(
                    0,
                    curve("reference".into(), first.steps.iter().map(|s| (s.time_s, target(s))).collect(), 0, true),
                );
            }
            Panel { title: format!("{title}: {name}"), x_label: "time (s)", y_label, curves, equal_aspect: false }
        };
    let panels = [
        over_time("altitude", "z (m)", |s| s.position_m.z, Some(|s| s.target_m.z)),
        over_time("airspeed (pitot)", "m/s", |s| s.airspeed_mps, None),
        over_time("roll", "deg", |s| s.euler_rad[0].to_degrees(), None),
        over_time("pitch", "deg", |s| s.euler_rad[1].to_degrees(), None),
    ];
    draw(&attitude, (1100, 1000), &panels, (4, 1))?;
    Ok(vec![path_3d, path_views, error, joints, attitude])
}

/// `summary.csv`: the printed table, a row per metric and a column per controller (`metric,NAME,...`).
pub fn write_summary_csv(summaries: &[(&str, TrackingSummary)], path: &Path) -> Result<(), OutputError> {
    let error = |e: &dyn std::fmt::Display| OutputError::Write { path: path.to_owned(), message: e.to_string() };
    let tables: Vec<Vec<(String, String)>> = summaries.iter().map(|(_, s)| s.rows()).collect();
    let mut out = csv::Writer::from_writer(Vec::new());
    out.write_record(std::iter::once("metric").chain(summaries.iter().map(|(name, _)| *name)))
        .map_err(|e| error(&e))?;
    for (k, (label, _)) in tables.first().map_or(&[][..], Vec::as_slice).iter().enumerate() {
        out.write_record(std::iter::once(label.as_str()).chain(tables.iter().map(|t| t[k].1.as_str())))
            .map_err(|e| error(&e))?;
    }
    let bytes = out.into_inner().map_err(|e| error(&e))?;
    flapper_plot::write_atomically(path, &bytes).map_err(|e| error(&e))
}

/// `start.json`: the recorded episode's initial state ([`crate::tracking::EpisodeStart`]), every number
/// written so that it reads back to the same f64.
pub fn write_start_json(record: &EpisodeTrace, path: &Path) -> Result<(), OutputError> {
    let text = serde_json::to_string_pretty(&record.start).expect("numbers serialize");
    flapper_plot::write_atomically(path, text.as_bytes())
        .map_err(|e| OutputError::Write { path: path.to_owned(), message: e.to_string() })
}

/// A row of `observations.csv`: the step, what the controller observed (named by the observation layout)
/// and the actions it chose.
#[derive(serde::Serialize)]
struct ObservationRow<'a> {
    step: usize,
    observation: &'a [f32],
    action: &'a [f32],
}

/// `observations.csv`: `step`, the observation's `names`, then `action_q1`..`action_q5`, a row per
/// control step of the recorded episode.
pub fn write_observations_csv(record: &EpisodeTrace, names: &[String], path: &Path) -> Result<(), OutputError> {
    let mut header = vec!["step".to_owned()];
    header.extend(names.iter().cloned());
    header.extend((1..=record.actions.first().map_or(N_ACTUATED_JOINTS, Vec::len)).map(|k| format!("action_q{k}")));
    let rows = record.observations.iter().zip(&record.actions).enumerate();
    let rows = rows.map(|(step, (observation, action))| ObservationRow { step, observation, action });
    write_csv_rows(path, &header, rows)
        .map_err(|e| OutputError::Write { path: path.to_owned(), message: e.to_string() })
}
