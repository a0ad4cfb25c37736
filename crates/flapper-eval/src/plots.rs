//! Pictures of a flight, as SVG: altitude and speed against time, joint angles and their targets over
//! the last second (as in the paper's Fig. 3), and the path seen from above and from the side.

use std::path::{Path, PathBuf};

use flapper_sim::{ActuatedJoint, Vec3};
use plotters::coord::Shift;
use plotters::prelude::*;

use crate::OutputError;
use crate::flight_log::FlightLog;

/// One curve of a panel.
struct Curve {
    label: String,
    points: Vec<(f64, f64)>,
    color: RGBColor,
    dashed: bool,
}

/// A chart of curves sharing axes.
struct Panel<'a> {
    title: String,
    x_label: &'a str,
    y_label: &'a str,
    curves: Vec<Curve>,
    /// Same scale on both axes (for paths).
    equal_aspect: bool,
}

const COLORS: [RGBColor; 5] =
    [RGBColor(31, 119, 180), RGBColor(214, 39, 40), RGBColor(44, 160, 44), RGBColor(255, 127, 14), RGBColor(148, 103, 189)];

/// Writes `altitude_speed.svg`, `joints.svg` and `path.svg` into `dir`; returns their paths.
pub fn write_flight_plots(log: &FlightLog, dir: &Path, title: &str) -> Result<Vec<PathBuf>, OutputError> {
    let rows = log.rows();
    let series = |f: &dyn Fn(&crate::FlightRow) -> (f64, f64)| rows.iter().map(f).collect::<Vec<_>>();
    let curve = |label: &str, points, color, dashed| Curve { label: label.to_owned(), points, color, dashed };

    let altitude = Panel {
        title: format!("{title}: altitude"),
        x_label: "time (s)",
        y_label: "altitude (m)",
        curves: vec![curve("z", series(&|r| (r.state.time_s, r.state.position_m.z)), COLORS[0], false)],
        equal_aspect: false,
    };
    let speed = Panel {
        title: "speed".into(),
        x_label: "time (s)",
        y_label: "speed (m/s)",
        curves: vec![
            curve("ground speed", series(&|r| (r.state.time_s, r.state.velocity_mps.length())), COLORS[0], false),
            curve("pitot airspeed", series(&|r| (r.state.time_s, r.state.airspeed_mps)), COLORS[1], false),
        ],
        equal_aspect: false,
    };
    let altitude_path = dir.join("altitude_speed.svg");
    draw(&altitude_path, (900, 700), &[altitude, speed], (2, 1))?;

    // Joints over the last second: at 5.3 Hz a longer window is unreadable.
    let t_end = rows.last().map_or(0.0, |r| r.state.time_s);
    let window: Vec<_> = rows.iter().filter(|r| r.state.time_s >= t_end - 1.0).collect();
    let joint_panel = |title: &'static str, joints: &[ActuatedJoint]| Panel {
        title: title.into(),
        x_label: "time (s)",
        y_label: "angle (deg)",
        curves: joints
            .iter()
            .enumerate()
            .flat_map(|(k, joint)| {
                let i = joint.index();
                let angle = window.iter().map(|r| (r.state.time_s, r.state.joint_positions_rad[i].to_degrees())).collect();
                let target = window.iter().map(|r| (r.state.time_s, r.applied_rad[i].to_degrees())).collect();
                [
                    curve(joint.name(), angle, COLORS[k], false),
                    curve(&format!("{} target", joint.name()), target, COLORS[k], true),
                ]
            })
            .collect(),
        equal_aspect: false,
    };
    let joints_path = dir.join("joints.svg");
    draw(
        &joints_path,
        (900, 900),
        &[
            joint_panel("wing flap (last 1 s)", &[ActuatedJoint::FlapLeft, ActuatedJoint::FlapRight]),
            joint_panel("wing pitch (last 1 s)", &[ActuatedJoint::PitchLeft, ActuatedJoint::PitchRight]),
            joint_panel("tail pitch (last 1 s)", &[ActuatedJoint::TailPitch]),
        ],
        (3, 1),
    )?;

    let path_path = dir.join("path.svg");
    let positions: Vec<Vec3> = rows.iter().map(|r| r.state.position_m).collect();
    write_path_views(&positions, title, &path_path)?;
    Ok(vec![altitude_path, joints_path, path_path])
}

/// Writes the top (x-y) and side (x-z) views of a path of points to `path` (SVG).
pub fn write_path_views(points: &[Vec3], title: &str, path: &Path) -> Result<(), OutputError> {
    let view = |name: &str, pick: fn(&Vec3) -> (f64, f64), y_label: &'static str| Panel {
        title: format!("{title}: {name}"),
        x_label: "x (m)",
        y_label,
        curves: vec![Curve { label: "path".into(), points: points.iter().map(pick).collect(), color: COLORS[0], dashed: false }],
        equal_aspect: true,
    };
    let top = view("top view", |p| (p.x, p.y), "y (m)");
    let side = view("side view", |p| (p.x, p.z), "z (m)");
    draw(path, (1000, 800), &[top, side], (2, 1))
}

fn draw(path: &Path, size: (u32, u32), panels: &[Panel], grid: (usize, usize)) -> Result<(), OutputError> {
    let error = |e: &dyn std::fmt::Display| OutputError::Write { path: path.to_owned(), message: e.to_string() };
    let root = SVGBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| error(&e))?;
    for (area, panel) in root.split_evenly(grid).iter().zip(panels) {
        draw_panel(area, panel).map_err(|e| error(&e))?;
    }
    root.present().map_err(|e| error(&e))
}

fn draw_panel(area: &DrawingArea<SVGBackend, Shift>, panel: &Panel) -> Result<(), Box<dyn std::error::Error>> {
    let points = panel.curves.iter().flat_map(|c| c.points.iter()).filter(|(x, y)| x.is_finite() && y.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y) in points {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !x0.is_finite() {
        (x0, x1, y0, y1) = (0.0, 1.0, 0.0, 1.0);
    }
    let pad = |lo: f64, hi: f64| {
        let span = (hi - lo).max(1e-3);
        (lo - 0.05 * span, hi + 0.05 * span)
    };
    let ((mut x0, mut x1), (mut y0, mut y1)) = (pad(x0, x1), pad(y0, y1));
    if panel.equal_aspect {
        // Widen the shorter range so a metre is a metre both ways (plot areas are about 2:1 wide).
        let (dx, dy) = (x1 - x0, y1 - y0);
        let (px, py) = (area.dim_in_pixel().0 as f64 - 80.0, area.dim_in_pixel().1 as f64 - 70.0);
        let scale = (dx / px).max(dy / py);
        let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
        (x0, x1) = (cx - 0.5 * scale * px, cx + 0.5 * scale * px);
        (y0, y1) = (cy - 0.5 * scale * py, cy + 0.5 * scale * py);
    }
    let mut chart = ChartBuilder::on(area)
        .caption(&panel.title, ("sans-serif", 18))
        .margin(8)
        .x_label_area_size(35)
        .y_label_area_size(55)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart.configure_mesh().x_desc(panel.x_label).y_desc(panel.y_label).light_line_style(WHITE.mix(0.0)).draw()?;
    for curve in &panel.curves {
        let color = curve.color;
        let style = ShapeStyle { color: color.to_rgba(), filled: false, stroke_width: if curve.dashed { 1 } else { 2 } };
        let label = curve.label.clone();
        if curve.dashed {
            chart
                .draw_series(DashedLineSeries::new(curve.points.iter().copied(), 6, 4, style))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(1)));
        } else {
            chart
                .draw_series(LineSeries::new(curve.points.iter().copied(), style))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
        }
    }
    if panel.curves.len() > 1 {
        chart.configure_series_labels().background_style(WHITE.mix(0.8)).border_style(BLACK).draw()?;
    }
    Ok(())
}
