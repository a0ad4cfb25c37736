//! The "efficient bird" trade-off: per controller, how closely it tracks against what it spends. Each
//! trained policy (and once the scripted gait, on the same randomized starts) flies the longitudinal
//! reference as `flapper eval` flies it, and its energy per metre there is divided by the scripted
//! gait's (the energy ratio); beside it the glide fraction of longitudinal's glide segment (as
//! `flapper modes` measures it), the flap's fundamental in cruise (as `flapper eval` prints it) and the
//! straight level 3.0 m/s path. Downstream of evaluation and [`crate::modes`]; the report and
//! `flapper frontier` show it as `frontier.csv` ([`file`]), `energy_vs_tracking.svg` and
//! `energy_vs_slow_flight.svg` ([`figure`]).

pub mod figure;
pub mod file;
mod measure;

pub use measure::{FrontierPolicy, FrontierSettings, energy_ratio, measure_frontier, step_count};

use serde::{Deserialize, Serialize};

/// The reference whose energy per metre and tracking error the trade-off is drawn from.
pub const ENERGY_REFERENCE: &str = "longitudinal";
/// The reference whose flap fundamental is reported (the cruise gait).
pub const CRUISE_REFERENCE: &str = "cruise";
/// The straight level 3.0 m/s path, from the repository's root: slow flight.
pub const LEVEL_3_REFERENCE: &str = "examples/level-3.0mps.csv";
/// The efficient-bird bar on energy: at most this many times the scripted gait's energy per metre.
pub const ENERGY_RATIO_BAR: f64 = 1.5;
/// The tracking bar on longitudinal: a mean RMS position error of at most this (m).
pub const TRACKING_BAR_M: f64 = 0.3;
/// The slow-flight bar on the level 3.0 m/s path: a mean RMS position error of at most this (m)...
pub const SLOW_FLIGHT_BAR_M: f64 = 0.5;
/// ...with at least this share of its episodes completed.
pub const SLOW_FLIGHT_COMPLETED_SHARE: f64 = 0.95;
/// The flap frequencies of the paper's cruise, "4-6 Hz" (Hz): the efficient bird's flap bar.
pub const CRUISE_FLAP_BAND_HZ: (f64, f64) = (4.0, 6.0);

/// One controller's point on the trade-off: a row of `frontier.csv`. A figure not measured (a flight
/// that did not complete for the glide fraction, a point measured elsewhere without it) is `None`,
/// an empty field in the file.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct FrontierRow {
    /// The controller's name in the table and the figure.
    pub label: String,
    /// Its policy file (empty for the scripted gait).
    #[serde(default)]
    pub policy: String,
    /// `flapper eval --reference longitudinal`: episodes completed, of how many.
    pub longitudinal_completed: Option<usize>,
    pub longitudinal_episodes: Option<usize>,
    /// Mean over the episodes of each episode's RMS position error (m).
    #[serde(serialize_with = "flapper_files::decimals::optional_fixed::<4, _>")]
    pub longitudinal_rms_m: Option<f64>,
    /// Absolute mechanical energy over the distance flown, mean over the episodes (J/m).
    #[serde(serialize_with = "flapper_files::decimals::optional_fixed::<3, _>")]
    pub longitudinal_j_per_m: Option<f64>,
    /// The scripted gait's, on the same starts of the same reference (J/m).
    #[serde(serialize_with = "flapper_files::decimals::optional_fixed::<3, _>")]
    pub scripted_j_per_m: Option<f64>,
    /// `longitudinal_j_per_m` over `scripted_j_per_m`.
    #[serde(serialize_with = "flapper_files::decimals::optional_fixed::<3, _>")]
    pub energy_ratio: Option<f64>,
    /// Share of longitudinal's glide segment flown with the wings held (`flapper modes`, exact start).
    #[serde(serialize_with = "flapper_files::decimals::optional_fixed::<3, _>")]
    pub glide_fraction: Option<f64>,
    /// flap_left's fundamental on the cruise reference, mean over the episodes (Hz).
    #[serde(serialize_with = "flapper_files::decimals::optional_fixed::<3, _>")]
    pub cruise_flap_hz: Option<f64>,
    /// The level 3.0 m/s path: episodes completed, mean RMS error (m), of how many episodes.
    pub level3_completed: Option<usize>,
    #[serde(serialize_with = "flapper_files::decimals::optional_fixed::<4, _>")]
    pub level3_rms_m: Option<f64>,
    pub level3_episodes: Option<usize>,
    /// The command that measured the row (with its episodes and seed, and where it ran if it matters).
    pub source: String,
}

impl FrontierRow {
    /// Whether the row meets the efficient bird's three flight bars at once: at most
    /// [`ENERGY_RATIO_BAR`] times the scripted gait's energy per metre, the wings held through at least
    /// [`crate::modes::GLIDING_SEGMENT_FRACTION`] of the glide segment, and a cruise flap within
    /// [`CRUISE_FLAP_BAND_HZ`]. A figure not measured meets nothing.
    pub fn meets_flight_bars(&self) -> bool {
        let (low, high) = CRUISE_FLAP_BAND_HZ;
        self.energy_ratio.is_some_and(|ratio| ratio <= ENERGY_RATIO_BAR)
            && self.glide_fraction.is_some_and(|glide| glide >= crate::modes::GLIDING_SEGMENT_FRACTION)
            && self.cruise_flap_hz.is_some_and(|hz| (low..=high).contains(&hz))
    }
}

/// The columns of `frontier.csv`, in [`FrontierRow`]'s order (a test keeps them in step).
pub const COLUMNS: [&str; 14] = [
    "label",
    "policy",
    "longitudinal_completed",
    "longitudinal_episodes",
    "longitudinal_rms_m",
    "longitudinal_j_per_m",
    "scripted_j_per_m",
    "energy_ratio",
    "glide_fraction",
    "cruise_flap_hz",
    "level3_completed",
    "level3_rms_m",
    "level3_episodes",
    "source",
];

/// A measured trade-off: the policies' rows in the order given, and the scripted gait's.
#[derive(Debug, Clone, PartialEq)]
pub struct Frontier {
    pub policies: Vec<FrontierRow>,
    pub scripted: FrontierRow,
    /// What could not be measured and why (one line each).
    pub notes: Vec<String>,
    /// Randomized starts per reference, and their seed.
    pub episodes: usize,
    pub seed: u64,
}

impl Frontier {
    /// Every row: the policies, then the scripted gait.
    pub fn rows(&self) -> impl Iterator<Item = &FrontierRow> {
        self.policies.iter().chain(std::iter::once(&self.scripted))
    }
}

/// Writes `frontier.csv` (the measured rows, then `points`, rows measured elsewhere),
/// `energy_vs_tracking.svg` and `energy_vs_slow_flight.svg` into `dir`; returns their paths.
pub fn write_frontier_files(
    dir: &std::path::Path,
    frontier: &Frontier,
    points: &[FrontierRow],
) -> Result<[std::path::PathBuf; 3], crate::AnalysisError> {
    let csv = dir.join(file::FRONTIER_CSV);
    file::write_frontier_csv(&csv, frontier.rows().chain(points))?;
    let draw = |axis: figure::TrackingAxis| {
        let svg = dir.join(axis.file_name());
        figure::draw_frontier(&svg, frontier, points, axis)
            .map_err(|message| crate::AnalysisError::Write { path: svg.clone(), message })?;
        Ok::<_, crate::AnalysisError>(svg)
    };
    Ok([csv, draw(figure::TrackingAxis::Longitudinal)?, draw(figure::TrackingAxis::SlowFlight)?])
}

/// The printed table of `rows` (the CLI's and the report page's): a header and a row of cells each, "-"
/// where a figure is missing.
pub fn table<'a>(rows: impl IntoIterator<Item = &'a FrontierRow>) -> (Vec<String>, Vec<Vec<String>>) {
    let header = [
        "controller",
        "longitudinal",
        "RMS (m)",
        "J/m",
        "scripted J/m",
        "energy ratio",
        "glide fraction",
        "cruise flap (Hz)",
        "level 3 m/s",
        "RMS (m)",
    ];
    let number = |value: Option<f64>, decimals: usize| value.map_or_else(|| "-".into(), |v| format!("{v:.decimals$}"));
    let count = |completed: Option<usize>, episodes: Option<usize>| match (completed, episodes) {
        (Some(c), Some(n)) => format!("{c}/{n}"),
        (Some(c), None) => c.to_string(),
        _ => "-".into(),
    };
    let cells = rows
        .into_iter()
        .map(|r| {
            vec![
                r.label.clone(),
                count(r.longitudinal_completed, r.longitudinal_episodes),
                number(r.longitudinal_rms_m, 3),
                number(r.longitudinal_j_per_m, 2),
                number(r.scripted_j_per_m, 2),
                number(r.energy_ratio, 2),
                number(r.glide_fraction, 2),
                number(r.cruise_flap_hz, 2),
                count(r.level3_completed, r.level3_episodes),
                number(r.level3_rms_m, 3),
            ]
        })
        .collect();
    (header.map(String::from).to_vec(), cells)
}
