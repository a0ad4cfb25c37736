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

/// The named reference whose segments these are (`flapper reference --list`).
pub const LONGITUDINAL: &str = "longitudinal";
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
pub const SETTLE_S: f64 = 2.0;

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
    named_from_exact_start(robot, controller, task, LONGITUDINAL)
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
    let held = held_along(&flight.steps, dt_s);
    let segments: Vec<SegmentFigures> = SEGMENTS
        .iter()
        .map(|&(segment, start_s, end_s)| {
            let inside = segment_indices(&flight.steps, start_s, end_s);
            segment_figures(&flight.steps, &inside, &held, dt_s, segment, start_s, end_s)
        })
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

/// The indices of the steps inside a segment, after the launch transient.
fn segment_indices(steps: &[TrackingStep], start_s: f64, end_s: f64) -> Vec<usize> {
    (0..steps.len()).filter(|&k| steps[k].time_s >= start_s.max(SETTLE_S) && steps[k].time_s < end_s).collect()
}

/// One segment of the longitudinal reference over many flights from randomized starts (`flapper eval
/// --reference longitudinal`): [`SegmentFigures`]' power, energy and glide, and the tracking error, each
/// the mean over the flights that flew the segment to its end (each flight weighed alike), where `flapper
/// modes` reads one flight from the exact start.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SegmentOverFlights {
    pub segment: &'static str,
    pub start_s: f64,
    pub end_s: f64,
    /// The flights that flew the segment to its end, and all flown.
    pub flights: usize,
    pub episodes: usize,
    #[serde(serialize_with = "flapper_files::decimals::fixed::<2, _>")]
    pub mean_absolute_power_w: f64,
    #[serde(serialize_with = "flapper_files::decimals::fixed::<3, _>")]
    pub mean_error_m: f64,
    #[serde(serialize_with = "flapper_files::decimals::fixed::<3, _>")]
    pub energy_per_metre_j: f64,
    #[serde(serialize_with = "flapper_files::decimals::fixed::<3, _>")]
    pub glide_fraction: f64,
}

/// Each of [`SEGMENTS`] over `flights` (the longitudinal reference flown from many starts, a control
/// step `dt_s` apart); NaN figures for a segment no flight flew to its end.
pub fn segments_over_flights(flights: &[EpisodeResult], dt_s: f64) -> Vec<SegmentOverFlights> {
    let measured: Vec<(&EpisodeResult, Vec<bool>)> =
        flights.iter().map(|flight| (flight, held_along(&flight.steps, dt_s))).collect();
    SEGMENTS
        .iter()
        .map(|&(segment, start_s, end_s)| {
            // Flown to its end: a step within one control period of it.
            let through: Vec<&(&EpisodeResult, Vec<bool>)> =
                measured.iter().filter(|(f, _)| f.steps.last().is_some_and(|s| s.time_s >= end_s - dt_s)).collect();
            let per_flight: Vec<(SegmentFigures, f64)> = through
                .iter()
                .map(|(flight, held)| {
                    let inside = segment_indices(&flight.steps, start_s, end_s);
                    let figures = segment_figures(&flight.steps, &inside, held, dt_s, segment, start_s, end_s);
                    let error =
                        inside.iter().map(|&k| flight.steps[k].error_m).sum::<f64>() / inside.len().max(1) as f64;
                    (figures, error)
                })
                .collect();
            let mean = |value: &dyn Fn(&(SegmentFigures, f64)) -> f64| {
                if per_flight.is_empty() {
                    f64::NAN
                } else {
                    per_flight.iter().map(value).sum::<f64>() / per_flight.len() as f64
                }
            };
            SegmentOverFlights {
                segment,
                start_s,
                end_s,
                flights: per_flight.len(),
                episodes: flights.len(),
                mean_absolute_power_w: mean(&|(f, _)| f.mean_absolute_power_w),
                mean_error_m: mean(&|(_, error)| *error),
                energy_per_metre_j: mean(&|(f, _)| f.energy_per_metre_j),
                glide_fraction: mean(&|(f, _)| f.glide_fraction),
            }
        })
        .collect()
}

/// `segments.csv`: [`segments_over_flights`]' rows.
pub fn write_segments_csv(path: &Path, rows: &[SegmentOverFlights]) -> Result<(), AnalysisError> {
    flapper_files::write_csv_records(path, rows)
        .map_err(|e| AnalysisError::Write { path: path.to_owned(), message: e.to_string() })
}

/// One segment's figures from the steps inside it (`indices`, from [`segment_indices`]).
fn segment_figures(
    steps: &[TrackingStep],
    indices: &[usize],
    held: &[bool],
    dt_s: f64,
    segment: &'static str,
    start_s: f64,
    end_s: f64,
) -> SegmentFigures {
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

/// [`held_wings`] of the left flap along a flight's steps.
fn held_along(steps: &[TrackingStep], dt_s: f64) -> Vec<bool> {
    let flap = ActuatedJoint::FlapLeft.index();
    let angles: Vec<f64> = steps.iter().map(|s| s.joint_positions_rad[flap]).collect();
    held_wings(&angles, dt_s)
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

    /// A flight of `seconds` at 4 m/s along x with 10 W of absolute power and an error of `error_m`,
    /// flapping 50 deg at 5 Hz before `held_from_s` and holding its wing after.
    fn flight(seconds: f64, held_from_s: f64, error_m: f64) -> EpisodeResult {
        let dt = 0.02;
        let steps = (0..=(seconds / dt).round() as usize)
            .map(|k| {
                let t = k as f64 * dt;
                let mut joints = [0.0; flapper_sim::N_ACTUATED_JOINTS];
                if t < held_from_s {
                    joints[ActuatedJoint::FlapLeft.index()] =
                        50f64.to_radians() * (std::f64::consts::TAU * 5.0 * t).sin();
                }
                TrackingStep {
                    episode: 0,
                    time_s: t,
                    position_m: flapper_sim::Vec3::new(4.0 * t, 0.0, 0.0),
                    target_m: flapper_sim::Vec3::new(4.0 * t + error_m, 0.0, 0.0),
                    error_m,
                    airspeed_mps: 4.0,
                    euler_rad: [0.0; 3],
                    joint_positions_rad: joints,
                    joint_velocities_radps: [0.0; flapper_sim::N_ACTUATED_JOINTS],
                    joint_targets_rad: joints,
                    mechanical_power_w: 10.0,
                    absolute_power_w: 10.0,
                }
            })
            .collect();
        let end = if seconds >= 24.0 {
            flapper_task::termination::EpisodeEnd::ReferenceEnd
        } else {
            flapper_task::termination::EpisodeEnd::TooFarFromTarget
        };
        EpisodeResult { end, steps, wind_mps: flapper_sim::Vec3::ZERO }
    }

    #[test]
    fn segments_over_flights_weigh_each_flight_that_flew_the_segment_alike() {
        // One flight glides from 12 s on; one flaps to the end; one falls at 10 s, inside the climb.
        let flights = [flight(24.0, 12.0, 0.1), flight(24.0, 99.0, 0.3), flight(10.0, 99.0, 0.5)];
        let rows = segments_over_flights(&flights, 0.02);
        let names: Vec<&str> = rows.iter().map(|r| r.segment).collect();
        assert_eq!(names, ["cruise", "climb", "glide", "dive"]);
        assert_eq!(rows.iter().map(|r| (r.flights, r.episodes)).collect::<Vec<_>>(), [(3, 3), (2, 3), (2, 3), (2, 3)]);
        // The fallen flight counts in the cruise only.
        assert!((rows[0].mean_error_m - 0.3).abs() < 1e-12, "{}", rows[0].mean_error_m);
        assert!((rows[1].mean_error_m - 0.2).abs() < 1e-12, "{}", rows[1].mean_error_m);
        // 10 W at 4 m/s: 2.5 J/m in every segment (n steps' energy over n - 1 steps' distance: 1% more).
        for row in &rows {
            assert!((row.mean_absolute_power_w - 10.0).abs() < 1e-12, "{row:?}");
            assert!((row.energy_per_metre_j - 2.5).abs() < 0.02, "{row:?}");
        }
        // The gliding flight holds its wing over the glide segment but the window's half after 12 s; the
        // other flaps: a mean of about one half. The dive: one flight held throughout, one flapping.
        assert_eq!(rows[1].glide_fraction, 0.0);
        let glide = rows[2].glide_fraction;
        assert!((glide - 0.5 * (6.0 - 0.2) / 6.0).abs() < 0.01, "{glide}");
        assert!((rows[3].glide_fraction - 0.5).abs() < 1e-12, "{}", rows[3].glide_fraction);
    }

    #[test]
    fn a_segment_no_flight_reached_reads_nan() {
        let rows = segments_over_flights(&[flight(5.0, 99.0, 0.1)], 0.02);
        assert_eq!(rows[0].flights, 0);
        assert!(rows.iter().all(|r| r.mean_absolute_power_w.is_nan() && r.glide_fraction.is_nan()));
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
