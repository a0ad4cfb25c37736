//! The trade-off's figures, a point per controller with the efficient-bird bars drawn: the energy ratio
//! against longitudinal's RMS error (`energy_vs_tracking.svg`), and against the level 3.0 m/s path's
//! (`energy_vs_slow_flight.svg`: the frontier between slow flight and the efficient bird). The
//! controllers measured by the run are labelled; the experiments' points (a cloud of a hundred and more)
//! are coloured by whether they meet the three flight bars and labelled only where a label fits, the
//! CSV beside the figure naming every one.

use std::path::Path;

use flapper_plot::{COLORS, Guide, LabelledPoint, Labels, PointGroup, Scatter};

use super::{
    CRUISE_FLAP_BAND_HZ, ENERGY_RATIO_BAR, ENERGY_REFERENCE, Frontier, FrontierRow, SLOW_FLIGHT_BAR_M,
    SLOW_FLIGHT_COMPLETED_SHARE, TRACKING_BAR_M,
};
use crate::modes::GLIDING_SEGMENT_FRACTION;

/// The figure of energy against longitudinal's tracking.
pub const FRONTIER_SVG: &str = "energy_vs_tracking.svg";
/// The figure of energy against slow flight.
pub const SLOW_FLIGHT_SVG: &str = "energy_vs_slow_flight.svg";

/// The error a figure puts against the energy ratio.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrackingAxis {
    /// Longitudinal's mean RMS position error.
    Longitudinal,
    /// The level 3.0 m/s path's, for a controller that completes it in at least
    /// [`SLOW_FLIGHT_COMPLETED_SHARE`] of its episodes (one that falls out of slow flight has no point).
    SlowFlight,
}

impl TrackingAxis {
    /// The file the figure is written to.
    pub fn file_name(self) -> &'static str {
        match self {
            TrackingAxis::Longitudinal => FRONTIER_SVG,
            TrackingAxis::SlowFlight => SLOW_FLIGHT_SVG,
        }
    }

    /// A row's x: its error on this axis, if measured (and, for slow flight, flown).
    pub fn error_m(self, row: &FrontierRow) -> Option<f64> {
        match self {
            TrackingAxis::Longitudinal => row.longitudinal_rms_m,
            TrackingAxis::SlowFlight => {
                let (completed, episodes) = (row.level3_completed?, row.level3_episodes?);
                let held = episodes > 0 && completed as f64 >= SLOW_FLIGHT_COMPLETED_SHARE * episodes as f64;
                if held { row.level3_rms_m } else { None }
            }
        }
    }
}

/// Draws `frontier` (filled: the policies and the scripted gait, measured by the run, each labelled)
/// and `points` (rings: measured in experiments, as their `source` says; those meeting the three flight
/// bars, [`FrontierRow::meets_flight_bars`], in a colour of their own and labelled first) into `path`,
/// the energy ratio against `axis`'s error. A row without both is left out of the figure (it stays in
/// the CSV).
pub fn draw_frontier(
    path: &Path,
    frontier: &Frontier,
    points: &[FrontierRow],
    axis: TrackingAxis,
) -> Result<(), String> {
    let labelled = |rows: &mut dyn Iterator<Item = &FrontierRow>| -> Vec<LabelledPoint> {
        rows.filter_map(|r| Some(LabelledPoint { x: axis.error_m(r)?, y: r.energy_ratio?, label: r.label.clone() }))
            .collect()
    };
    let mut groups = vec![
        PointGroup {
            legend: "measured here".into(),
            color: COLORS[0],
            filled: true,
            labels: Labels::Every,
            points: labelled(&mut frontier.policies.iter()),
        },
        PointGroup {
            legend: "scripted gait (ratio 1 by definition)".into(),
            color: COLORS[2],
            filled: true,
            labels: Labels::Every,
            points: labelled(&mut std::iter::once(&frontier.scripted)),
        },
    ];
    let (low_hz, high_hz) = CRUISE_FLAP_BAND_HZ;
    let experiments = [
        (
            true,
            format!(
                "experiments meeting the flight bars (energy, glide {GLIDING_SEGMENT_FRACTION}, flap {low_hz}-{high_hz} Hz)"
            ),
            COLORS[1],
        ),
        (false, "other experiments (labelled where room; every one in frontier.csv)".to_string(), COLORS[3]),
    ];
    for (meeting, legend, color) in experiments {
        let mut rows = points.iter().filter(|r| r.meets_flight_bars() == meeting);
        let points = labelled(&mut rows);
        if !points.is_empty() {
            groups.push(PointGroup { legend, color, filled: false, labels: Labels::WhereTheyFit, points });
        }
    }
    let (runs, seed) = (frontier.episodes, frontier.seed);
    let (title, x_label, error_bar) = match axis {
        TrackingAxis::Longitudinal => (
            format!("energy against tracking on {ENERGY_REFERENCE} ({runs} episodes, seed {seed})"),
            "longitudinal: mean RMS position error (m)",
            Guide::Vertical { x: TRACKING_BAR_M, label: format!("tracking bar: {TRACKING_BAR_M} m") },
        ),
        TrackingAxis::SlowFlight => (
            format!(
                "energy on {ENERGY_REFERENCE} against slow flight (level 3 m/s, completed in at least {:.0}% of \
                 {runs} episodes, seed {seed})",
                SLOW_FLIGHT_COMPLETED_SHARE * 100.0
            ),
            "level 3.0 m/s: mean RMS position error (m)",
            Guide::Vertical { x: SLOW_FLIGHT_BAR_M, label: format!("slow-flight bar: {SLOW_FLIGHT_BAR_M} m") },
        ),
    };
    let scatter = Scatter {
        title,
        x_label,
        y_label: "energy per metre / the scripted gait's",
        groups,
        guides: vec![
            Guide::Horizontal {
                y: ENERGY_RATIO_BAR,
                label: format!("energy bar: {ENERGY_RATIO_BAR} x the scripted gait"),
            },
            Guide::Horizontal { y: 1.0, label: "the scripted gait's energy".into() },
            error_bar,
        ],
    };
    flapper_plot::draw_scatter(path, (1000, 700), &scatter)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(completed: usize, episodes: usize, rms: f64) -> FrontierRow {
        FrontierRow {
            label: "a".into(),
            longitudinal_rms_m: Some(0.2),
            energy_ratio: Some(1.3),
            level3_completed: Some(completed),
            level3_episodes: Some(episodes),
            level3_rms_m: Some(rms),
            ..FrontierRow::default()
        }
    }

    #[test]
    fn slow_flight_is_placed_only_where_it_is_flown_in_95_percent_of_episodes() {
        assert_eq!(TrackingAxis::SlowFlight.error_m(&row(95, 100, 0.4)), Some(0.4));
        assert_eq!(TrackingAxis::SlowFlight.error_m(&row(94, 100, 0.4)), None, "94 of 100 falls out of it");
        assert_eq!(TrackingAxis::SlowFlight.error_m(&row(0, 0, 0.4)), None, "no episodes, no point");
        assert_eq!(TrackingAxis::SlowFlight.error_m(&FrontierRow::default()), None, "not measured");
        assert_eq!(TrackingAxis::Longitudinal.error_m(&row(0, 100, 0.4)), Some(0.2), "longitudinal's own");
    }

    #[test]
    fn the_flight_bars_ask_energy_glide_and_flap_together() {
        let bird = FrontierRow {
            energy_ratio: Some(1.5),
            glide_fraction: Some(0.5),
            cruise_flap_hz: Some(6.0),
            ..row(0, 0, 0.0)
        };
        assert!(bird.meets_flight_bars(), "each bar met at its edge");
        assert!(!FrontierRow { energy_ratio: Some(1.51), ..bird.clone() }.meets_flight_bars(), "energy");
        assert!(!FrontierRow { glide_fraction: Some(0.49), ..bird.clone() }.meets_flight_bars(), "glide");
        assert!(!FrontierRow { cruise_flap_hz: Some(3.99), ..bird.clone() }.meets_flight_bars(), "flap below 4 Hz");
        assert!(!FrontierRow { cruise_flap_hz: Some(6.01), ..bird.clone() }.meets_flight_bars(), "flap above 6 Hz");
        assert!(!FrontierRow { glide_fraction: None, ..bird.clone() }.meets_flight_bars(), "not measured");
    }
}
