//! The report's pictures: the robot annotated (Fig. 1), snapshots overlaid along the loop, the sharp
//! turn and the roll-off-the-bottom with the reference points (Fig. 2, 10), a chase-camera video of
//! the aerobatic flight, and the aerobatic path coloured by manoeuvre (Fig. 11).

use std::path::Path;

use flapper_eval::tracking::{EpisodeResult, TrackingStep};
use flapper_plot::{COLORS, Curve, Panel, RGBColor};
use flapper_render::{
    CameraView, FlightRenderer, Marker, Pose, RenderError, VideoEncoder, chase_cameras, framing_camera, write_png,
};
use flapper_sim::RobotModel;

use crate::ReportError;
use crate::experiments::Tracked;

const VIDEO_FPS: u32 = 25;
const REFERENCE_MARKER: [f32; 4] = [0.85, 0.15, 0.1, 0.9];

fn pose(step: &TrackingStep) -> Pose {
    Pose::from_euler(step.position_m.to_array(), step.euler_rad, step.joint_positions_rad)
}

/// The episode to show: the first that completed, else the first.
fn shown(tracked: &Tracked) -> &EpisodeResult {
    tracked.results.iter().find(|r| r.completed()).unwrap_or(&tracked.results[0])
}

/// Reference points from `start_s` to `end_s`, every `every_s`, as markers.
fn reference_markers(tracked: &Tracked, start_s: f64, end_s: f64, every_s: f64, radius_m: f64) -> Vec<Marker> {
    let stride = ((every_s / tracked.period_s).round() as usize).max(1);
    tracked
        .reference
        .points()
        .iter()
        .enumerate()
        .filter(|(k, _)| k % stride == 0 && (start_s..=end_s).contains(&(*k as f64 * tracked.period_s)))
        .map(|(_, p)| Marker { position_m: p.to_array(), radius_m, rgba: REFERENCE_MARKER })
        .collect()
}

/// Fig. 1 and the overlays: `render/robot.png`, `render/<reference>.png`.
pub fn snapshots(
    robot: &RobotModel,
    manoeuvres: &[&Tracked],
    (width, height): (usize, usize),
    dir: &Path,
) -> Result<(), RenderError> {
    std::fs::create_dir_all(dir).map_err(|e| RenderError::Write { path: dir.display().to_string(), source: e })?;
    let mut renderer = FlightRenderer::new(robot, width, height)?;
    // Fig. 1: wings raised and pitched, seen from the front left and above.
    renderer.set_annotated(true);
    let at = [0.0, 0.0, 1.2];
    let robot_pose = Pose::from_euler(at, [0.0, -0.1, 0.0], [0.35, -0.15, 0.35, -0.15, -0.1]);
    let camera = CameraView { lookat_m: at, distance_m: 1.3, azimuth_deg: 215.0, elevation_deg: -22.0 };
    write_png(&renderer.render(&robot_pose, &camera)?, &dir.join("robot.png"))?;
    renderer.set_annotated(false);

    let aspect = width as f64 / height as f64;
    for tracked in manoeuvres {
        let (from_s, to_s, every_s) = match flapper_task::reference::named::manoeuvre_window_s(&tracked.name) {
            Some((start_s, end_s)) => (start_s - 0.6, end_s + 0.6, if end_s - start_s < 1.5 { 0.2 } else { 0.3 }),
            // No manoeuvre: the whole flight, about 25 snapshots.
            None => (0.0, tracked.reference.duration_s(), (tracked.reference.duration_s() / 25.0).max(0.2)),
        };
        let episode = shown(tracked);
        let (azimuth_deg, elevation_deg) = view_of(episode, from_s, to_s);
        let stride = ((every_s / tracked.period_s).round() as usize).max(1);
        let poses: Vec<Pose> =
            episode.steps.iter().filter(|s| (from_s..=to_s).contains(&s.time_s)).step_by(stride).map(pose).collect();
        let markers = reference_markers(tracked, from_s, to_s, 0.1, 0.035);
        let mut points: Vec<[f64; 3]> = poses.iter().map(|p| p.position_m).collect();
        points.extend(markers.iter().map(|m| m.position_m));
        let camera = framing_camera(&points, azimuth_deg, elevation_deg, aspect, renderer.fovy_deg())
            .ok_or(RenderError::Empty("no poses in the manoeuvre"))?;
        renderer.set_markers(markers)?;
        write_png(&renderer.overlay(&poses, &camera)?, &dir.join(format!("{}.png", file_stem(&tracked.name))))?;
    }
    Ok(())
}

/// A name usable as a file name (a CSV reference's name may hold a path).
pub(crate) fn file_stem(name: &str) -> String {
    let stem = Path::new(name).file_stem().map_or(name.to_owned(), |s| s.to_string_lossy().into_owned());
    stem.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}

/// Where to look from: from the side (the x-z plane, where loops climb) when the path between
/// `from_s` and `to_s` spans more height than width across, else from above.
fn view_of(episode: &EpisodeResult, from_s: f64, to_s: f64) -> (f64, f64) {
    let inside = episode.steps.iter().filter(|s| (from_s..=to_s).contains(&s.time_s));
    let (mut y, mut z) = ((f64::MAX, f64::MIN), (f64::MAX, f64::MIN));
    for s in inside {
        y = (y.0.min(s.position_m.y), y.1.max(s.position_m.y));
        z = (z.0.min(s.position_m.z), z.1.max(s.position_m.z));
    }
    if z.1 - z.0 >= y.1 - y.0 { (75.0, -10.0) } else { (90.0, -80.0) }
}

/// A flight from a chase camera: `<name>.mp4`, and the frame in the middle of its manoeuvre (or of
/// the flight) as `<name>_poster.png`, written even without ffmpeg.
pub fn video(
    robot: &RobotModel,
    aerobatic: &Tracked,
    (width, height): (usize, usize),
    dir: &Path,
) -> Result<(), RenderError> {
    std::fs::create_dir_all(dir).map_err(|e| RenderError::Write { path: dir.display().to_string(), source: e })?;
    let mut renderer = FlightRenderer::new(robot, width, height)?;
    let episode = shown(aerobatic);
    let stride = ((1.0 / (VIDEO_FPS as f64 * aerobatic.period_s)).round() as usize).max(1);
    let steps: Vec<&TrackingStep> = episode.steps.iter().step_by(stride).collect();
    let positions: Vec<[f64; 3]> = steps.iter().map(|s| s.position_m.to_array()).collect();
    let cameras = chase_cameras(&positions, VIDEO_FPS as f64, 2.6, -12.0);
    renderer.set_markers(reference_markers(aerobatic, 0.0, aerobatic.reference.duration_s(), 0.2, 0.05))?;
    let stem = file_stem(&aerobatic.name);
    // The poster: the middle of the first loop, else of the manoeuvre, else of the flight.
    let poster_s = flapper_task::reference::named::piece_spans(&aerobatic.name)
        .and_then(|spans| spans.iter().find(|s| s.0 == "loop").map(|s| 0.5 * (s.1 + s.2)))
        .or_else(|| flapper_task::reference::named::manoeuvre_window_s(&aerobatic.name).map(|(s, e)| 0.5 * (s + e)))
        .unwrap_or(0.5 * aerobatic.reference.duration_s());
    let poster_index = steps.iter().position(|s| s.time_s >= poster_s).unwrap_or(0);
    write_png(
        &renderer.render(&pose(steps[poster_index]), &cameras[poster_index])?,
        &dir.join(format!("{stem}_poster.png")),
    )?;
    let mut encoder = VideoEncoder::start(&dir.join(format!("{stem}.mp4")), width, height, VIDEO_FPS)?;
    for (step, camera) in steps.iter().zip(&cameras) {
        encoder.push(&renderer.render(&pose(step), camera)?)?;
    }
    encoder.finish()?;
    Ok(())
}

/// Fig. 11: the aerobatic reference and one flight, top and side views, each piece in its
/// manoeuvre's colour: `render/aerobatic_manoeuvres.svg`.
pub fn aerobatic_manoeuvres(aerobatic: &Tracked, dir: &Path) -> Result<(), ReportError> {
    let spans = flapper_task::reference::named::piece_spans(&aerobatic.name).unwrap_or_default();
    let episode = shown(aerobatic);
    let mut labels: Vec<&str> = Vec::new();
    for (label, _, _) in &spans {
        if !labels.contains(label) {
            labels.push(label);
        }
    }
    let colour = |label: &str| -> RGBColor {
        let k = labels.iter().position(|l| *l == label).unwrap_or(0);
        [RGBColor(120, 120, 120), COLORS[1], COLORS[2], COLORS[3], COLORS[4], COLORS[0], RGBColor(140, 86, 75)][k % 7]
    };
    let view = |title: &str, pick: fn(&flapper_sim::Vec3) -> (f64, f64), y_label| {
        let reference: Vec<(f64, f64)> = episode.steps.iter().map(|s| pick(&s.target_m)).collect();
        let mut curves =
            vec![Curve { label: "reference".into(), points: reference, color: RGBColor(0, 0, 0), dashed: true }];
        let mut named: Vec<&str> = Vec::new();
        for (label, start_s, end_s) in &spans {
            let points: Vec<(f64, f64)> = episode
                .steps
                .iter()
                .filter(|s| s.time_s >= *start_s && s.time_s <= *end_s + 1e-9)
                .map(|s| pick(&s.position_m))
                .collect();
            let first = !named.contains(label);
            named.push(label);
            curves.push(Curve {
                label: if first { (*label).to_owned() } else { String::new() },
                points,
                color: colour(label),
                dashed: false,
            });
        }
        Panel {
            title: format!("aerobatic, flown by the policy: {title}"),
            x_label: "x (m)",
            y_label,
            curves,
            equal_aspect: true,
        }
    };
    let path = dir.join("aerobatic_manoeuvres.svg");
    std::fs::create_dir_all(dir).map_err(|e| ReportError::Write { path: dir.to_owned(), message: e.to_string() })?;
    flapper_plot::draw(
        &path,
        (1100, 1000),
        &[view("top view", |p| (p.x, p.y), "y (m)"), view("side view", |p| (p.x, p.z), "z (m)")],
        (2, 1),
    )
    .map_err(|message| ReportError::Write { path, message })
}
