//! Flight modes along the paper's longitudinal reference (cruise, climb +0.8 m/s, glide -0.83 m/s,
//! dive -1.5 m/s, 6 s each at 3.8 m/s): per segment the flap amplitude, its fundamental frequency and
//! energy fraction, the mechanical power, the energy per metre flown and the share of the time spent
//! gliding (wings held, no flapping cycle), to answer whether the policy glides ("gliding instead of
//! flapping when possible") or flaps throughout. Flown from an exact start.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_eval::spectrum::fundamental;
use flapper_eval::tracking::{EpisodeResult, TrackingController, TrackingStep, energy_per_metre_j, evaluate_tracking};
use flapper_plot::{COLORS, Curve, Panel};
use flapper_ppo::ActorCritic;
use flapper_sim::{ActuatedJoint, RobotModel};
use flapper_task::TaskConfig;
use flapper_task::flap_rhythm::peak_to_peak;
use flapper_task::reference::NAMED_START_M;
use flapper_task::reference::named::named;
use serde::{Deserialize, Serialize};

use crate::AnalysisError;

/// The longitudinal reference's segments: name, start and end (s).
pub const SEGMENTS: [(&str, f64, f64); 4] =
    [("cruise", 0.0, 6.0), ("climb", 6.0, 12.0), ("glide", 12.0, 18.0), ("dive", 18.0, 24.0)];
/// Index of the glide segment in [`SEGMENTS`].
pub const GLIDE_SEGMENT: usize = 2;
/// A moment counts as gliding when the flap angle moves less than this, peak to peak, over the
/// [`GLIDE_WINDOW_S`] centred on it: the wings are held, no flapping cycle runs. (The cruise gait
/// flaps about 100 deg peak to peak.) The same range below which the reward's stroke detector
/// (`flapper_task::flap_rhythm`) reads no stroke, so a wing held by this measure pays no flap price.
pub const GLIDE_MAX_FLAP_RANGE_DEG: f64 = flapper_task::flap_rhythm::HELD_FLAP_RANGE_DEG;
/// Two cycles of the cruise gait's 5 Hz flapping: long enough that a flapping wing always moves
/// through its range within it.
pub const GLIDE_WINDOW_S: f64 = 0.4;
/// A segment glides when at least this share of its time is spent gliding.
pub const GLIDING_SEGMENT_FRACTION: f64 = 0.5;
/// The launch transient left out of the first segment (s).
const SETTLE_S: f64 = 2.0;

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SegmentFigures {
    pub segment: String,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub start_s: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub end_s: f64,
    /// Half the peak-to-peak angle of flap_left (deg).
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub flap_amplitude_deg: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub flap_fundamental_hz: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub flap_energy_fraction: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mean_power_w: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mean_absolute_power_w: f64,
    /// Absolute mechanical energy over the distance flown in the segment (J/m).
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub energy_per_metre_j: f64,
    /// Share of the segment's time spent gliding ([`held_wings`]).
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub glide_fraction: f64,
    /// `glide_fraction` at least [`GLIDING_SEGMENT_FRACTION`].
    pub glides: bool,
}

/// `modes.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ModesReport {
    pub segments: Vec<SegmentFigures>,
    pub verdict: String,
}

/// One flight along the longitudinal reference and its figures per segment.
pub struct FlightModes {
    pub report: ModesReport,
    pub steps: Vec<TrackingStep>,
    /// Per step, whether the wings are held ([`held_wings`]).
    pub held: Vec<bool>,
}

impl FlightModes {
    /// The share of the glide segment flown with the wings held: what "does it glide?" is decided on.
    pub fn glide_segment_fraction(&self) -> f64 {
        self.report.segments[GLIDE_SEGMENT].glide_fraction
    }
}

/// Flies the longitudinal reference once from its exact start with `controller` (the policy, or the
/// scripted gait for comparison), as far as it gets (the scripted gait falls behind in the climb; its
/// energy per metre is still what evaluation compares with).
pub fn longitudinal_from_exact_start(
    robot: &RobotModel,
    controller: &TrackingController,
    task: &TaskConfig,
) -> Result<EpisodeResult, AnalysisError> {
    named_from_exact_start(robot, controller, task, "longitudinal")
}

/// Flies the named reference `name` (`flapper reference --list`) once from its exact start with
/// `controller`, as far as it gets.
pub fn named_from_exact_start(
    robot: &RobotModel,
    controller: &TrackingController,
    task: &TaskConfig,
    name: &str,
) -> Result<EpisodeResult, AnalysisError> {
    let exact = crate::exact_start(task);
    let dt_s = exact.control_period_s(robot.timestep_s());
    let lookahead_s = exact.observation.lookahead_steps as f64 * dt_s;
    let reference = Arc::new(
        named(name, NAMED_START_M, dt_s, lookahead_s)
            .ok_or_else(|| AnalysisError::UnknownReference(name.to_owned()))?,
    );
    Ok(evaluate_tracking(robot, controller, &exact, reference, 1, 1)?.remove(0))
}

/// Flies the longitudinal reference once from its exact start and measures each segment; writes nothing.
pub fn measure_flight_modes(
    robot: &RobotModel,
    policy: Arc<ActorCritic>,
    task: &TaskConfig,
) -> Result<FlightModes, AnalysisError> {
    measure_controller_flight_modes(robot, &TrackingController::Policy(policy), task)
}

/// [`measure_flight_modes`] for any controller that tracks a reference (the scripted gait too, on
/// its own task).
pub fn measure_controller_flight_modes(
    robot: &RobotModel,
    controller: &TrackingController,
    task: &TaskConfig,
) -> Result<FlightModes, AnalysisError> {
    let flight = longitudinal_from_exact_start(robot, controller, task)?;
    if !flight.completed() {
        let at = flight.steps.last().map_or(0.0, |s| s.time_s);
        return Err(AnalysisError::FlightFailed {
            what: "longitudinal reference".into(),
            end: flight.end.name(),
            time_s: at,
        });
    }
    let dt_s = task.control_period_s(robot.timestep_s());
    let flap = ActuatedJoint::FlapLeft.index();
    let flap_angles: Vec<f64> = flight.steps.iter().map(|s| s.joint_positions_rad[flap]).collect();
    let held = held_wings(&flap_angles, dt_s);
    let segments: Vec<SegmentFigures> = SEGMENTS
        .iter()
        .map(|&(segment, start_s, end_s)| segment_figures(&flight.steps, &held, dt_s, segment, start_s, end_s))
        .collect();
    let gliding: Vec<&str> = segments.iter().filter(|s| s.glides).map(|s| s.segment.as_str()).collect();
    let verdict = if gliding.is_empty() {
        format!(
            "no: the wings are held {:.0}% of the glide segment and {:.0}% of the dive (a segment glides from {:.0}%)",
            100.0 * segments[GLIDE_SEGMENT].glide_fraction,
            100.0 * segments[GLIDE_SEGMENT + 1].glide_fraction,
            100.0 * GLIDING_SEGMENT_FRACTION
        )
    } else {
        format!("yes, in: {}", gliding.join(", "))
    };
    Ok(FlightModes { report: ModesReport { segments, verdict }, steps: flight.steps, held })
}

/// [`measure_flight_modes`], then `modes.json` and `modes.svg` in `dir`.
pub fn flight_modes(
    robot: &RobotModel,
    policy: Arc<ActorCritic>,
    task: &TaskConfig,
    dir: &Path,
) -> Result<(ModesReport, Vec<PathBuf>), AnalysisError> {
    let fail =
        |path: &Path, e: &dyn std::fmt::Display| AnalysisError::Write { path: path.to_owned(), message: e.to_string() };
    let measured = measure_flight_modes(robot, policy, task)?;
    let json = dir.join("modes.json");
    flapper_files::write_json(&json, &measured.report).map_err(|e| fail(&json, &e))?;
    let svg = dir.join("modes.svg");
    draw_modes(&svg, &measured.steps, &measured.held, &measured.report).map_err(|e| fail(&svg, &e))?;
    Ok((measured.report, vec![json, svg]))
}

/// `modes.svg`: the flap angle, the power, the held wings and the energy per metre over the flight,
/// with the segments' boundaries.
fn draw_modes(svg: &Path, steps: &[TrackingStep], held: &[bool], report: &ModesReport) -> Result<(), String> {
    let flap = ActuatedJoint::FlapLeft.index();
    let boundaries = |lo: f64, hi: f64| -> Vec<Curve> {
        SEGMENTS[1..]
            .iter()
            .map(|&(name, start, _)| Curve {
                label: format!("{name} from {start} s"),
                points: vec![(start, lo), (start, hi)],
                color: COLORS[4],
                dashed: true,
            })
            .collect()
    };
    let flap_points: Vec<(f64, f64)> =
        steps.iter().map(|s| (s.time_s, s.joint_positions_rad[flap].to_degrees())).collect();
    let power_points: Vec<(f64, f64)> = steps.iter().map(|s| (s.time_s, s.absolute_power_w)).collect();
    let max_power = power_points.iter().map(|p| p.1).fold(0.0, f64::max);
    let mut flap_curves =
        vec![Curve { label: "flap_left".into(), points: flap_points, color: COLORS[0], dashed: false }];
    flap_curves.extend(boundaries(-60.0, 60.0));
    let mut power_curves = vec![Curve {
        label: "absolute mechanical power".into(),
        points: power_points,
        color: COLORS[1],
        dashed: false,
    }];
    power_curves.extend(boundaries(0.0, max_power));
    let held_points: Vec<(f64, f64)> =
        steps.iter().zip(held).map(|(s, &h)| (s.time_s, if h { 1.0 } else { 0.0 })).collect();
    let per_segment = |value: &dyn Fn(&SegmentFigures) -> f64| -> Vec<(f64, f64)> {
        report.segments.iter().flat_map(|s| [(s.start_s, value(s)), (s.end_s, value(s))]).collect()
    };
    let mut glide_curves = vec![
        Curve { label: "wings held (1) or flapping (0)".into(), points: held_points, color: COLORS[2], dashed: false },
        Curve {
            label: "glide fraction of the segment".into(),
            points: per_segment(&|s| s.glide_fraction),
            color: COLORS[3],
            dashed: false,
        },
    ];
    glide_curves.extend(boundaries(0.0, 1.0));
    let energy = per_segment(&|s| s.energy_per_metre_j);
    let max_energy = energy.iter().map(|p| p.1).filter(|e| e.is_finite()).fold(0.0, f64::max);
    let mut energy_curves = vec![Curve {
        label: "energy per metre of the segment".into(),
        points: energy,
        color: COLORS[1],
        dashed: false,
    }];
    energy_curves.extend(boundaries(0.0, max_energy));
    let panels = [
        Panel {
            title: "longitudinal reference: flap angle (cruise | climb | glide | dive)".into(),
            x_label: "time (s)",
            y_label: "deg",
            curves: flap_curves,
            equal_aspect: false,
        },
        Panel {
            title: "mechanical power".into(),
            x_label: "time (s)",
            y_label: "W",
            curves: power_curves,
            equal_aspect: false,
        },
        Panel {
            title: format!(
                "gliding: flap range below {GLIDE_MAX_FLAP_RANGE_DEG} deg over the {GLIDE_WINDOW_S} s around each moment"
            ),
            x_label: "time (s)",
            y_label: "share",
            curves: glide_curves,
            equal_aspect: false,
        },
        Panel {
            title: "absolute mechanical energy per metre flown, per segment".into(),
            x_label: "time (s)",
            y_label: "J/m",
            curves: energy_curves,
            equal_aspect: false,
        },
    ];
    flapper_plot::draw(svg, (1200, 1400), &panels, (4, 1))
}

/// One segment's figures from the steps inside it (after the launch transient).
fn segment_figures(
    steps: &[TrackingStep],
    held: &[bool],
    dt_s: f64,
    segment: &'static str,
    start_s: f64,
    end_s: f64,
) -> SegmentFigures {
    let inside_at = |k: &usize| steps[*k].time_s >= start_s.max(SETTLE_S) && steps[*k].time_s < end_s;
    let indices: Vec<usize> = (0..steps.len()).filter(inside_at).collect();
    let inside: Vec<&TrackingStep> = indices.iter().map(|&k| &steps[k]).collect();
    let flap = ActuatedJoint::FlapLeft.index();
    let angles: Vec<f64> = inside.iter().map(|s| s.joint_positions_rad[flap]).collect();
    let found = fundamental(&angles, 1.0 / dt_s);
    let n = inside.len().max(1) as f64;
    let mean = |f: &dyn Fn(&TrackingStep) -> f64| inside.iter().map(|s| f(s)).sum::<f64>() / n;
    let glide_fraction = indices.iter().filter(|&&k| held[k]).count() as f64 / n;
    SegmentFigures {
        segment: segment.to_owned(),
        start_s,
        end_s,
        flap_amplitude_deg: (0.5 * peak_to_peak(&angles)).to_degrees(),
        flap_fundamental_hz: found.map_or(f64::NAN, |f| f.frequency_hz),
        flap_energy_fraction: found.map_or(f64::NAN, |f| f.energy_fraction),
        mean_power_w: mean(&|s| s.mechanical_power_w),
        mean_absolute_power_w: mean(&|s| s.absolute_power_w),
        energy_per_metre_j: energy_per_metre_j(&inside, dt_s),
        glide_fraction,
        glides: glide_fraction >= GLIDING_SEGMENT_FRACTION,
    }
}

/// Per sample of a flap angle sampled every `dt_s`: whether the wing is held (gliding), that is
/// whether the angle's peak-to-peak range over the [`GLIDE_WINDOW_S`] centred on the sample (cut at
/// the ends of the flight) is below [`GLIDE_MAX_FLAP_RANGE_DEG`].
pub fn held_wings(flap_rad: &[f64], dt_s: f64) -> Vec<bool> {
    let half = ((0.5 * GLIDE_WINDOW_S / dt_s).round() as usize).max(1);
    let limit = GLIDE_MAX_FLAP_RANGE_DEG.to_radians();
    (0..flap_rad.len())
        .map(|k| peak_to_peak(&flap_rad[k.saturating_sub(half)..(k + half + 1).min(flap_rad.len())]) < limit)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_held_wing_glides_and_a_flapping_one_does_not() {
        let dt = 0.02;
        // 4 s flapping 50 deg at 5 Hz, then 4 s held at -3 deg with a 2 deg wobble.
        let flap: Vec<f64> = (0..400)
            .map(|k| {
                let t = k as f64 * dt;
                if t < 4.0 {
                    50f64.to_radians() * (std::f64::consts::TAU * 5.0 * t).sin()
                } else {
                    (-3.0 + 2.0 * (std::f64::consts::TAU * 5.0 * t).sin()).to_radians()
                }
            })
            .collect();
        let held = held_wings(&flap, dt);
        assert!(held[..190].iter().all(|h| !h), "flapping counted as gliding");
        assert!(held[210..].iter().all(|&h| h), "a held wing counted as flapping");
        let share = held.iter().filter(|&&h| h).count() as f64 / held.len() as f64;
        // The window's half (0.2 s) after the wings stop still sees the last flap.
        assert!((share - (4.0 - 0.2) / 8.0).abs() < 0.005, "{share}");
    }

    #[test]
    fn slow_flapping_within_the_window_is_still_flapping() {
        // 2.5 Hz, the slowest a bird-like gait would flap: one cycle per window.
        let dt = 0.02;
        let flap: Vec<f64> =
            (0..200).map(|k| 20f64.to_radians() * (std::f64::consts::TAU * 2.5 * k as f64 * dt).sin()).collect();
        assert!(held_wings(&flap, dt).iter().all(|h| !h));
    }
}
