//! `energy_vs_tracking.svg`: the energy ratio against longitudinal's RMS error, a labelled point per
//! controller, with the efficient-bird bars drawn.

use std::path::Path;

use flapper_plot::{COLORS, Guide, LabelledPoint, PointGroup, Scatter};

use super::{ENERGY_RATIO_BAR, ENERGY_REFERENCE, Frontier, FrontierRow, TRACKING_BAR_M};

/// The figure a frontier run draws.
pub const FRONTIER_SVG: &str = "energy_vs_tracking.svg";

/// Draws `frontier` (filled: the policies and the scripted gait, measured by the run) and `points`
/// (rings: measured in experiments, as their `source` says) into `path`. A row without both its RMS
/// error and its energy ratio is left out of the figure (it stays in the CSV).
pub fn draw_frontier(path: &Path, frontier: &Frontier, points: &[FrontierRow]) -> Result<(), String> {
    let labelled = |rows: &mut dyn Iterator<Item = &FrontierRow>| -> Vec<LabelledPoint> {
        rows.filter_map(|r| {
            Some(LabelledPoint { x: r.longitudinal_rms_m?, y: r.energy_ratio?, label: r.label.clone() })
        })
        .collect()
    };
    let mut groups = vec![
        PointGroup {
            legend: "measured here".into(),
            color: COLORS[0],
            filled: true,
            points: labelled(&mut frontier.policies.iter()),
        },
        PointGroup {
            legend: "scripted gait (ratio 1 by definition)".into(),
            color: COLORS[2],
            filled: true,
            points: labelled(&mut std::iter::once(&frontier.scripted)),
        },
    ];
    if !points.is_empty() {
        groups.push(PointGroup {
            legend: "measured in experiments".into(),
            color: COLORS[3],
            filled: false,
            points: labelled(&mut points.iter()),
        });
    }
    let scatter = Scatter {
        title: format!(
            "energy against tracking on {ENERGY_REFERENCE} ({} episodes, seed {})",
            frontier.episodes, frontier.seed
        ),
        x_label: "longitudinal: mean RMS position error (m)",
        y_label: "energy per metre / the scripted gait's",
        groups,
        guides: vec![
            Guide::Horizontal {
                y: ENERGY_RATIO_BAR,
                label: format!("energy bar: {ENERGY_RATIO_BAR} x the scripted gait"),
            },
            Guide::Horizontal { y: 1.0, label: "the scripted gait's energy".into() },
            Guide::Vertical { x: TRACKING_BAR_M, label: format!("tracking bar: {TRACKING_BAR_M} m") },
        ],
    };
    flapper_plot::draw_scatter(path, (1000, 700), &scatter)
}
