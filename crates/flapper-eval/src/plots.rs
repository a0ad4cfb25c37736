//! Pictures of a flight, as SVG: altitude and speed against time, joint angles and their targets over
//! the last second (as in the paper's Fig. 3), and the path seen from above and from the side.

use std::path::{Path, PathBuf};

use flapper_plot::{COLORS, Curve, Panel};
use flapper_sim::{ActuatedJoint, N_ACTUATED_JOINTS, Vec3};

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
    let window: Vec<JointSample> = rows
        .iter()
        .filter(|r| r.state.time_s >= t_end - 1.0)
        .map(|r| JointSample {
            time_s: r.state.time_s,
            angles_rad: r.state.joint_positions_rad,
            targets_rad: r.applied_rad,
        })
        .collect();
    let joints_path = dir.join("joints.svg");
    write_joint_window(&window, "last 1 s", &joints_path)?;

    let path_path = dir.join("path.svg");
    let positions: Vec<Vec3> = rows.iter().map(|r| r.state.position_m).collect();
    write_path_views(&positions, title, &path_path)?;
    Ok(vec![altitude_path, joints_path, path_path])
}

/// Joint angles and their (filtered) PD targets at one control step.
pub(crate) struct JointSample {
    pub time_s: f64,
    pub angles_rad: [f64; N_ACTUATED_JOINTS],
    pub targets_rad: [f64; N_ACTUATED_JOINTS],
}

/// The paper's Fig. 3: flap, wing pitch and tail angles with their targets over a short window.
pub(crate) fn write_joint_window(window: &[JointSample], when: &str, path: &Path) -> Result<(), OutputError> {
    let joint_panel = |name: &str, joints: &[ActuatedJoint]| Panel {
        title: format!("{name} ({when})"),
        x_label: "time (s)",
        y_label: "angle (deg)",
        curves: joints
            .iter()
            .enumerate()
            .flat_map(|(k, joint)| {
                let i = joint.index();
                let series = |f: fn(&JointSample) -> [f64; N_ACTUATED_JOINTS]| {
                    window.iter().map(|s| (s.time_s, f(s)[i].to_degrees())).collect::<Vec<_>>()
                };
                [
                    Curve {
                        label: joint.name().into(),
                        points: series(|s| s.angles_rad),
                        color: COLORS[k],
                        dashed: false,
                    },
                    Curve {
                        label: format!("{} target", joint.name()),
                        points: series(|s| s.targets_rad),
                        color: COLORS[k],
                        dashed: true,
                    },
                ]
            })
            .collect(),
        equal_aspect: false,
    };
    draw(
        path,
        (900, 900),
        &[
            joint_panel("wing flap", &[ActuatedJoint::FlapLeft, ActuatedJoint::FlapRight]),
            joint_panel("wing pitch", &[ActuatedJoint::PitchLeft, ActuatedJoint::PitchRight]),
            joint_panel("tail pitch", &[ActuatedJoint::TailPitch]),
        ],
        (3, 1),
    )
}

/// Writes the top (x-y) and side (x-z) views of a path of points to `path` (SVG).
pub fn write_path_views(points: &[Vec3], title: &str, path: &Path) -> Result<(), OutputError> {
    let view = |name: &str, pick: fn(&Vec3) -> (f64, f64), y_label: &'static str| Panel {
        title: format!("{title}: {name}"),
        x_label: "x (m)",
        y_label,
        curves: vec![Curve {
            label: "path".into(),
            points: points.iter().map(pick).collect(),
            color: COLORS[0],
            dashed: false,
        }],
        equal_aspect: true,
    };
    let top = view("top view", |p| (p.x, p.y), "y (m)");
    let side = view("side view", |p| (p.x, p.z), "z (m)");
    draw(path, (1000, 800), &[top, side], (2, 1))
}

fn draw(path: &Path, size: (u32, u32), panels: &[Panel], grid: (usize, usize)) -> Result<(), OutputError> {
    flapper_plot::draw(path, size, panels, grid)
        .map_err(|message| OutputError::Write { path: path.to_owned(), message })
}
