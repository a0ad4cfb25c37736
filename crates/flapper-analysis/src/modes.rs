//! Flight modes along the paper's longitudinal reference (cruise, climb +0.8 m/s, glide -0.83 m/s,
//! dive -1.5 m/s, 6 s each at 3.8 m/s): per segment the flap amplitude, its fundamental frequency and
//! energy fraction, and the mechanical power, to answer whether the policy glides ("gliding instead of
//! flapping when possible") or flaps throughout. Flown from an exact start.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_eval::spectrum::fundamental;
use flapper_eval::tracking::{Pilot, evaluate_tracking};
use flapper_plot::{COLORS, Curve, Panel};
use flapper_ppo::ActorCritic;
use flapper_sim::{ActuatedJoint, RobotModel};
use flapper_task::TaskConfig;
use flapper_task::reference::NAMED_START_M;
use flapper_task::reference::named::named;
use serde::Serialize;

use crate::AnalysisError;

/// The longitudinal reference's segments: name, start and end (s).
pub const SEGMENTS: [(&str, f64, f64); 4] =
    [("cruise", 0.0, 6.0), ("climb", 6.0, 12.0), ("glide", 12.0, 18.0), ("dive", 18.0, 24.0)];
/// A segment counts as gliding when its flap amplitude is below this fraction of the cruise's.
pub const GLIDE_AMPLITUDE_FRACTION: f64 = 0.25;
/// The launch transient left out of the first segment (s).
const SETTLE_S: f64 = 2.0;

#[derive(Debug, Clone, Serialize)]
pub struct SegmentFigures {
    pub segment: &'static str,
    pub start_s: f64,
    pub end_s: f64,
    /// Half the peak-to-peak angle of flap_left (deg).
    pub flap_amplitude_deg: f64,
    pub flap_fundamental_hz: f64,
    pub flap_energy_fraction: f64,
    pub mean_power_w: f64,
    pub mean_absolute_power_w: f64,
    /// Flap amplitude below `GLIDE_AMPLITUDE_FRACTION` of the cruise segment's.
    pub glides: bool,
}

/// `modes.json`.
#[derive(Debug, Clone, Serialize)]
pub struct ModesReport {
    pub segments: Vec<SegmentFigures>,
    pub verdict: String,
}

pub fn flight_modes(
    robot: &RobotModel,
    policy: Arc<ActorCritic>,
    task: &TaskConfig,
    dir: &Path,
) -> Result<(ModesReport, Vec<PathBuf>), AnalysisError> {
    let fail =
        |path: &Path, e: &dyn std::fmt::Display| AnalysisError::Write { path: path.to_owned(), message: e.to_string() };
    let mut exact = task.clone();
    exact.initial_state.position_offset_m = [0.0; 3];
    exact.initial_state.speed_offset_mps = 0.0;
    exact.initial_state.attitude_offset_deg = 0.0;
    let dt_s = exact.control_period_s(robot.timestep_s());
    let lookahead_s = exact.observation.lookahead_steps as f64 * dt_s;
    let reference = Arc::new(named("longitudinal", NAMED_START_M, dt_s, lookahead_s).expect("a named reference"));
    let flight = evaluate_tracking(robot, &Pilot::Policy(policy), &exact, reference, 1, 1)?.remove(0);
    if !flight.completed() {
        let at = flight.steps.last().map_or(0.0, |s| s.time_s);
        return Err(AnalysisError::FlightFailed {
            what: "longitudinal reference".into(),
            end: flight.end.name(),
            time_s: at,
        });
    }
    let flap = ActuatedJoint::FlapLeft.index();
    let mut segments: Vec<SegmentFigures> = SEGMENTS
        .iter()
        .map(|&(segment, start_s, end_s)| {
            let inside: Vec<_> =
                flight.steps.iter().filter(|s| s.time_s >= start_s.max(SETTLE_S) && s.time_s < end_s).collect();
            let angles: Vec<f64> = inside.iter().map(|s| s.joint_positions_rad[flap]).collect();
            let (lo, hi) =
                angles.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &a| (lo.min(a), hi.max(a)));
            let found = fundamental(&angles, 50.0);
            let n = inside.len().max(1) as f64;
            SegmentFigures {
                segment,
                start_s,
                end_s,
                flap_amplitude_deg: (0.5 * (hi - lo)).to_degrees(),
                flap_fundamental_hz: found.map_or(f64::NAN, |f| f.frequency_hz),
                flap_energy_fraction: found.map_or(f64::NAN, |f| f.energy_fraction),
                mean_power_w: inside.iter().map(|s| s.mechanical_power_w).sum::<f64>() / n,
                mean_absolute_power_w: inside.iter().map(|s| s.absolute_power_w).sum::<f64>() / n,
                glides: false,
            }
        })
        .collect();
    let cruise_amplitude = segments[0].flap_amplitude_deg;
    for s in &mut segments {
        s.glides = s.flap_amplitude_deg < GLIDE_AMPLITUDE_FRACTION * cruise_amplitude;
    }
    let gliding: Vec<&str> = segments.iter().filter(|s| s.glides).map(|s| s.segment).collect();
    let verdict = if gliding.is_empty() {
        format!(
            "no: the policy flaps in every segment (glide {:.0} deg, dive {:.0} deg against {:.0} deg in cruise; gliding would be below {:.0}%)",
            segments[2].flap_amplitude_deg,
            segments[3].flap_amplitude_deg,
            cruise_amplitude,
            100.0 * GLIDE_AMPLITUDE_FRACTION
        )
    } else {
        format!("yes, in: {}", gliding.join(", "))
    };
    let report = ModesReport { segments, verdict };
    let json = dir.join("modes.json");
    flapper_plot::write_atomically(
        &json,
        serde_json::to_string_pretty(&report).map_err(|e| fail(&json, &e))?.as_bytes(),
    )
    .map_err(|e| fail(&json, &e))?;
    let svg = dir.join("modes.svg");
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
        flight.steps.iter().map(|s| (s.time_s, s.joint_positions_rad[flap].to_degrees())).collect();
    let power_points: Vec<(f64, f64)> = flight.steps.iter().map(|s| (s.time_s, s.absolute_power_w)).collect();
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
    ];
    flapper_plot::draw(&svg, (1200, 800), &panels, (2, 1)).map_err(|e| fail(&svg, &e))?;
    Ok((report, vec![json, svg]))
}
