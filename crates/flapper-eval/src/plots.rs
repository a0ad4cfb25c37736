//! Pictures of a flight, as SVG: altitude and speed against time, joint angles and their targets over
//! the last second (as in the paper's Fig. 3), and the path seen from above and from the side.

use std::path::{Path, PathBuf};

use flapper_sim::{ActuatedJoint, Vec3};
use flapper_plot::{COLORS, Curve, Panel};

use crate::OutputError;
use crate::flight_log::FlightLog;

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
    flapper_plot::draw(path, size, panels, grid).map_err(|message| OutputError::Write { path: path.to_owned(), message })
}
