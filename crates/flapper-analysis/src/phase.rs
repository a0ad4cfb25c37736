//! Phase portraits of the wings (paper IV-B, Fig. 6-7) and the numbers behind the paper's reading of
//! them: each orbit's cycle-to-cycle spread (closed, periodic orbits), flap amplitude and velocity
//! range and mean wing pitch in climb against cruise at 3 m/s, and the right wing against the left
//! while turning left. Each flight starts exactly on its reference; the first 4 s (launch) are left out.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_eval::tracking::{EpisodeResult, TrackingController, evaluate_tracking};
use flapper_plot::{COLORS, Curve, Panel};
use flapper_ppo::ActorCritic;
use flapper_sim::{ActuatedJoint, RobotModel};
use flapper_task::TaskConfig;
use flapper_task::reference::NAMED_START_M;
use flapper_task::reference::generator::{Piece, build};
use serde::{Deserialize, Serialize};

use crate::AnalysisError;

/// Seconds after the launch before portraits are drawn.
pub const SETTLE_S: f64 = 4.0;
/// Phase samples per cycle when cycles are compared.
const PHASE_POINTS: usize = 24;
/// An orbit counts as closed when its cycles spread by less than this (% of its size).
pub const CLOSED_ORBIT_SPREAD_PERCENT: f64 = 20.0;

/// A level or climbing straight flight, or a level turn, starting exactly on it, `seconds` long.
pub fn fly_command(
    robot: &RobotModel,
    policy: &Arc<ActorCritic>,
    task: &TaskConfig,
    forward_speed_mps: f64,
    vertical_speed_mps: f64,
    yaw_rate_degps: f64,
    seconds: f64,
) -> Result<EpisodeResult, AnalysisError> {
    let exact = crate::exact_start(task);
    let dt_s = exact.control_period_s(robot.timestep_s());
    let lookahead_s = (exact.observation.lookahead_steps + 2) as f64 * dt_s;
    let piece = Piece::Command {
        forward_speed_mps,
        vertical_speed_mps,
        yaw_rate_radps: yaw_rate_degps.to_radians(),
        duration_s: seconds + lookahead_s,
    };
    let reference = Arc::new(build("phase", &[piece], NAMED_START_M, 0.0, dt_s));
    Ok(evaluate_tracking(robot, &TrackingController::Policy(policy.clone()), &exact, reference, 1, 1)?.remove(0))
}

/// One joint's motion after the launch: angle (rad) and angular velocity (rad/s) every 20 ms.
#[derive(Debug, Clone, PartialEq)]
pub struct JointTrace {
    pub angle_rad: Vec<f64>,
    pub velocity_radps: Vec<f64>,
}

impl JointTrace {
    pub fn of(flight: &EpisodeResult, joint: ActuatedJoint) -> Self {
        let settled = flight.steps.iter().filter(|s| s.time_s >= SETTLE_S);
        let (angle_rad, velocity_radps) =
            settled.map(|s| (s.joint_positions_rad[joint.index()], s.joint_velocities_radps[joint.index()])).unzip();
        Self { angle_rad, velocity_radps }
    }

    pub fn mean_angle_rad(&self) -> f64 {
        self.angle_rad.iter().sum::<f64>() / self.angle_rad.len().max(1) as f64
    }

    /// Half the peak-to-peak angle.
    pub fn amplitude_rad(&self) -> f64 {
        half_range(&self.angle_rad)
    }

    /// Half the peak-to-peak angular velocity.
    pub fn velocity_amplitude_radps(&self) -> f64 {
        half_range(&self.velocity_radps)
    }

    /// How far the cycles of the orbit lie from their mean cycle: cycles are cut at the upward
    /// crossings of the mean angle, each resampled at 24 phase points; the RMS distance of every
    /// cycle's points from the mean cycle's, with angle and velocity each scaled by the mean cycle's
    /// range, in % (0: every cycle the same closed curve). NaN with fewer than 3 cycles.
    pub fn orbit_spread_percent(&self) -> f64 {
        let mean = self.mean_angle_rad();
        let a = &self.angle_rad;
        // Crossing times in samples, interpolated between the samples on either side.
        let crossings: Vec<f64> = (1..a.len())
            .filter(|&k| a[k - 1] < mean && a[k] >= mean)
            .map(|k| (k - 1) as f64 + (mean - a[k - 1]) / (a[k] - a[k - 1]))
            .collect();
        let cycles: Vec<Vec<(f64, f64)>> = crossings
            .windows(2)
            .filter(|w| w[1] - w[0] >= 4.0)
            .map(|w| {
                (0..PHASE_POINTS)
                    .map(|p| {
                        let x = w[0] + (w[1] - w[0]) * p as f64 / PHASE_POINTS as f64;
                        let (i, f) = (x.floor() as usize, x.fract());
                        let lerp = |s: &[f64]| s[i] + f * (s[(i + 1).min(s.len() - 1)] - s[i]);
                        (lerp(&self.angle_rad), lerp(&self.velocity_radps))
                    })
                    .collect()
            })
            .collect();
        if cycles.len() < 3 {
            return f64::NAN;
        }
        let n = cycles.len() as f64;
        let mean_cycle: Vec<(f64, f64)> = (0..PHASE_POINTS)
            .map(|p| (cycles.iter().map(|c| c[p].0).sum::<f64>() / n, cycles.iter().map(|c| c[p].1).sum::<f64>() / n))
            .collect();
        let range =
            |f: fn(&(f64, f64)) -> f64| 2.0 * half_range(&mean_cycle.iter().map(f).collect::<Vec<_>>()).max(1e-9);
        let (ra, rv) = (range(|p| p.0), range(|p| p.1));
        let squares: f64 = cycles
            .iter()
            .flat_map(|c| {
                c.iter().zip(&mean_cycle).map(|(p, m)| (((p.0 - m.0) / ra).powi(2) + ((p.1 - m.1) / rv).powi(2)) / 2.0)
            })
            .sum();
        100.0 * (squares / (n * PHASE_POINTS as f64)).sqrt()
    }
}

fn half_range(values: &[f64]) -> f64 {
    let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    if lo.is_finite() { 0.5 * (hi - lo) } else { f64::NAN }
}

/// A statement of the paper's, checked on this policy.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Claim {
    pub claim: String,
    pub ours: String,
    pub confirmed: bool,
}

/// One orbit's figures (degrees).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct OrbitFigures {
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mean_deg: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub amplitude_deg: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub velocity_amplitude_degps: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub orbit_spread_percent: f64,
}

/// A joint's name beside its orbit's figures, as `phase.json` lists them.
fn orbit(joint: &str, trace: &JointTrace) -> (String, OrbitFigures) {
    (joint.to_owned(), OrbitFigures::of(trace))
}

impl OrbitFigures {
    fn of(trace: &JointTrace) -> Self {
        Self {
            mean_deg: trace.mean_angle_rad().to_degrees(),
            amplitude_deg: trace.amplitude_rad().to_degrees(),
            velocity_amplitude_degps: trace.velocity_amplitude_radps().to_degrees(),
            orbit_spread_percent: trace.orbit_spread_percent(),
        }
    }
}

/// `phase.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PhaseReport {
    pub forward_speed_mps: f64,
    pub climb_rate_mps: f64,
    pub turn_rate_degps: f64,
    pub cruise: [(String, OrbitFigures); 2],
    pub climb: [(String, OrbitFigures); 2],
    /// Left and right wing (flap, pitch) while turning left; `None` when the policy cannot turn.
    pub turn_left: Option<[(String, OrbitFigures); 4]>,
    pub turn_skipped_because: Option<String>,
    pub claims: Vec<Claim>,
}

/// Settings of the phase flights (paper IV-B: 3 m/s forward; climb and turn rates are ours).
pub const PAPER_FORWARD_SPEED_MPS: f64 = 3.0;
pub const CLIMB_RATE_MPS: f64 = 0.8;
pub const TURN_RATE_DEGPS: f64 = 20.0;
const FLIGHT_S: f64 = 16.0;

/// Flies cruise, climb and a left turn; writes `phase.json`, `phase_climb.svg` and (if it turns)
/// `phase_turn.svg` into `dir`.
/// Cruise and climb at `forward_speed_mps` (the paper: [`PAPER_FORWARD_SPEED_MPS`]).
pub fn phase_portraits(
    robot: &RobotModel,
    policy: Arc<ActorCritic>,
    task: &TaskConfig,
    forward_speed_mps: f64,
    dir: &Path,
) -> Result<(PhaseReport, Vec<PathBuf>), AnalysisError> {
    let fail =
        |path: &Path, e: &dyn std::fmt::Display| AnalysisError::Write { path: path.to_owned(), message: e.to_string() };
    let cruise = fly_command(robot, &policy, task, forward_speed_mps, 0.0, 0.0, FLIGHT_S)?;
    let climb = fly_command(robot, &policy, task, forward_speed_mps, CLIMB_RATE_MPS, 0.0, FLIGHT_S)?;
    for (name, flight) in [("cruise", &cruise), ("climb", &climb)] {
        if !flight.completed() {
            let at = flight.steps.last().map_or(0.0, |s| s.time_s);
            return Err(AnalysisError::FlightFailed {
                what: format!("{name} at {forward_speed_mps} m/s"),
                end: flight.end.name(),
                time_s: at,
            });
        }
    }
    let turn = fly_command(robot, &policy, task, flapper_sim::CRUISE_SPEED_MPS, 0.0, TURN_RATE_DEGPS, FLIGHT_S)?;
    let turn_skipped_because = (!turn.completed()).then(|| {
        format!(
            "the policy cannot turn: a level left turn at {TURN_RATE_DEGPS} deg/s and {} m/s ended '{}' after {:.1} s",
            flapper_sim::CRUISE_SPEED_MPS,
            turn.end.name(),
            turn.steps.last().map_or(0.0, |s| s.time_s)
        )
    });
    let [cf, cp, lf, lp] = [
        JointTrace::of(&cruise, ActuatedJoint::FlapRight),
        JointTrace::of(&cruise, ActuatedJoint::PitchRight),
        JointTrace::of(&climb, ActuatedJoint::FlapRight),
        JointTrace::of(&climb, ActuatedJoint::PitchRight),
    ];
    let turn_traces = turn_skipped_because.is_none().then(|| {
        [ActuatedJoint::FlapLeft, ActuatedJoint::PitchLeft, ActuatedJoint::FlapRight, ActuatedJoint::PitchRight]
            .map(|j| JointTrace::of(&turn, j))
    });
    let mut closure = vec![("cruise flap", &cf), ("cruise pitch", &cp), ("climb flap", &lf), ("climb pitch", &lp)];
    if let Some([tlf, tlp, trf, trp]) = &turn_traces {
        closure.extend([
            ("turn left flap", tlf),
            ("turn left pitch", tlp),
            ("turn right flap", trf),
            ("turn right pitch", trp),
        ]);
    }
    let mut claims = vec![closed_orbits_claim(&closure)];
    claims.extend(climb_claims([&cf, &cp, &lf, &lp]));
    if let Some(traces) = &turn_traces {
        claims.extend(turn_claims(traces));
    }
    let report = PhaseReport {
        forward_speed_mps,
        climb_rate_mps: CLIMB_RATE_MPS,
        turn_rate_degps: TURN_RATE_DEGPS,
        cruise: [orbit("flap_right", &cf), orbit("pitch_right", &cp)],
        climb: [orbit("flap_right", &lf), orbit("pitch_right", &lp)],
        turn_left: turn_traces.as_ref().map(|[a, b, c, d]| {
            [orbit("flap_left", a), orbit("pitch_left", b), orbit("flap_right", c), orbit("pitch_right", d)]
        }),
        turn_skipped_because,
        claims,
    };
    let json = dir.join("phase.json");
    flapper_files::write_json(&json, &report).map_err(|e| fail(&json, &e))?;
    let mut written = vec![json];
    written.extend(draw_portraits(dir, forward_speed_mps, [&cf, &cp, &lf, &lp], turn_traces.as_ref())?);
    Ok((report, written))
}

/// Claim 1: every orbit closes: its cycle-to-cycle spread is below [`CLOSED_ORBIT_SPREAD_PERCENT`].
fn closed_orbits_claim(orbits: &[(&str, &JointTrace)]) -> Claim {
    let spreads: Vec<String> =
        orbits.iter().map(|(name, t)| format!("{name} {:.1}%", t.orbit_spread_percent())).collect();
    Claim {
        claim: format!(
            "flap and wing pitch follow closed, consistent periodic orbits (cycle-to-cycle spread below {CLOSED_ORBIT_SPREAD_PERCENT}% of the orbit's size)"
        ),
        ours: spreads.join(", "),
        confirmed: orbits.iter().all(|(_, t)| t.orbit_spread_percent() < CLOSED_ORBIT_SPREAD_PERCENT),
    }
}

/// Claims 2-3 (Fig. 6), from the right wing's flap and pitch in cruise and in the climb.
fn climb_claims([cf, cp, lf, lp]: [&JointTrace; 4]) -> [Claim; 2] {
    [
        Claim {
            claim: "climbing flaps over a larger range of angle and velocity than cruising".into(),
            ours: format!(
                "flap amplitude {:.1} vs {:.1} deg, velocity amplitude {:.0} vs {:.0} deg/s (climb vs cruise)",
                lf.amplitude_rad().to_degrees(),
                cf.amplitude_rad().to_degrees(),
                lf.velocity_amplitude_radps().to_degrees(),
                cf.velocity_amplitude_radps().to_degrees()
            ),
            confirmed: lf.amplitude_rad() > cf.amplitude_rad()
                && lf.velocity_amplitude_radps() > cf.velocity_amplitude_radps(),
        },
        Claim {
            claim: "climbing shifts the mean wing pitch negative (leading edge up)".into(),
            ours: format!(
                "mean wing pitch {:.1} vs {:.1} deg (climb vs cruise)",
                lp.mean_angle_rad().to_degrees(),
                cp.mean_angle_rad().to_degrees()
            ),
            confirmed: lp.mean_angle_rad() < cp.mean_angle_rad(),
        },
    ]
}

/// Claims 4-5 (Fig. 7), from both wings' flap and pitch while turning left.
fn turn_claims([tlf, tlp, trf, trp]: &[JointTrace; 4]) -> [Claim; 2] {
    [
        Claim {
            claim: "turning left, the right wing's mean flap is higher than the left's".into(),
            ours: format!(
                "mean flap right {:.1} vs left {:.1} deg",
                trf.mean_angle_rad().to_degrees(),
                tlf.mean_angle_rad().to_degrees()
            ),
            confirmed: trf.mean_angle_rad() > tlf.mean_angle_rad(),
        },
        Claim {
            claim: "turning left, the right wing pitches up (more negative mean pitch) than the left".into(),
            ours: format!(
                "mean pitch right {:.1} vs left {:.1} deg",
                trp.mean_angle_rad().to_degrees(),
                tlp.mean_angle_rad().to_degrees()
            ),
            confirmed: trp.mean_angle_rad() < tlp.mean_angle_rad(),
        },
    ]
}

/// `phase_climb.svg` (Fig. 6) and, when the turn was flown, `phase_turn.svg` (Fig. 7).
fn draw_portraits(
    dir: &Path,
    forward_speed_mps: f64,
    [cf, cp, lf, lp]: [&JointTrace; 4],
    turn_traces: Option<&[JointTrace; 4]>,
) -> Result<Vec<PathBuf>, AnalysisError> {
    let fail =
        |path: &Path, e: &dyn std::fmt::Display| AnalysisError::Write { path: path.to_owned(), message: e.to_string() };
    let orbit = |label: &str, t: &JointTrace, k: usize| Curve {
        label: label.to_string(),
        points: t.angle_rad.iter().zip(&t.velocity_radps).map(|(a, v)| (a.to_degrees(), v.to_degrees())).collect(),
        color: COLORS[k],
        dashed: false,
    };
    let panel = |title: String, curves| Panel {
        title,
        x_label: "angle (deg)",
        y_label: "angular velocity (deg/s)",
        curves,
        equal_aspect: false,
    };
    let mut written = Vec::new();
    let climb_svg = dir.join("phase_climb.svg");
    let panels = [
        panel(
            format!("right wing flap, cruise vs climb at {forward_speed_mps} m/s"),
            vec![orbit("cruise", cf, 0), orbit("climb", lf, 1)],
        ),
        panel("right wing pitch, cruise vs climb".into(), vec![orbit("cruise", cp, 0), orbit("climb", lp, 1)]),
    ];
    flapper_plot::draw(&climb_svg, (1200, 520), &panels, (1, 2)).map_err(|e| fail(&climb_svg, &e))?;
    written.push(climb_svg);
    if let Some([tlf, tlp, trf, trp]) = turn_traces {
        let turn_svg = dir.join("phase_turn.svg");
        let panels = [
            panel(
                format!("flap while turning left at {TURN_RATE_DEGPS} deg/s"),
                vec![orbit("left wing", tlf, 0), orbit("right wing", trf, 1)],
            ),
            panel(
                "wing pitch while turning left".into(),
                vec![orbit("left wing", tlp, 0), orbit("right wing", trp, 1)],
            ),
        ];
        flapper_plot::draw(&turn_svg, (1200, 520), &panels, (1, 2)).map_err(|e| fail(&turn_svg, &e))?;
        written.push(turn_svg);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flap-like trace at 4 Hz sampled at 50 Hz, its amplitude scaled per cycle by `scale(cycle)`.
    fn trace(scale: impl Fn(usize) -> f64) -> JointTrace {
        let w = std::f64::consts::TAU * 4.0;
        let (angle_rad, velocity_radps) = (0..500)
            .map(|k| {
                let t = k as f64 * 0.02;
                let a = 0.7 * scale((t * 4.0) as usize);
                (0.1 + a * (w * t).sin(), a * w * (w * t).cos())
            })
            .unzip();
        JointTrace { angle_rad, velocity_radps }
    }

    #[test]
    fn a_periodic_orbit_is_closed_and_a_wandering_one_is_not() {
        let periodic = trace(|_| 1.0);
        assert!(periodic.orbit_spread_percent() < 1.0, "{}", periodic.orbit_spread_percent());
        assert!((periodic.mean_angle_rad() - 0.1).abs() < 0.01);
        assert!((periodic.amplitude_rad() - 0.7).abs() < 0.05);
        // Every other cycle at a fifth of the amplitude: far from one closed curve.
        let wandering = trace(|cycle| if cycle % 2 == 0 { 1.0 } else { 0.2 });
        assert!(wandering.orbit_spread_percent() > CLOSED_ORBIT_SPREAD_PERCENT, "{}", wandering.orbit_spread_percent());
        let flat = JointTrace { angle_rad: vec![0.0; 100], velocity_radps: vec![0.0; 100] };
        assert!(flat.orbit_spread_percent().is_nan(), "no cycles, no verdict");
    }
}
