//! The power curve of level flight: what a metre of straight and level flight costs this robot at each
//! airspeed. The scripted gait's family (flap frequency, body-pitch trim, wing-pitch amplitude and
//! lead, tail trim; its altitude hold sets the flap amplitude) is flown straight and level from a cruise launch;
//! the cheapest gait that holds its altitude at each airspeed draws the curve, and trained policies
//! fly level paths at chosen speeds beside it.
//!
//! The efficient-bird bars compare a policy with the scripted gait at the gait's own airspeed (about
//! 3.4 m/s), whatever speed the reference asks. The curve says what part of a policy's cost is the
//! speed itself (drag grows with it) and what part is the way it flaps: a policy is judged against the
//! cheapest gait at the airspeed it flew, as well as against the scripted gait.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_eval::tracking::{TrackingController, TrackingStep, energy_per_metre_j, evaluate_tracking};
use flapper_eval::{FlightSpec, ScriptedGait, ScriptedGaitConfig, fly};
use flapper_plot::{COLORS, Curve, Panel};
use flapper_sim::RobotModel;
use serde::Serialize;

use crate::AnalysisError;
use crate::frontier::FrontierPolicy;
use crate::robustness::level_reference;

/// Each gait flies this long from its launch (s).
pub const GAIT_FLIGHT_S: f64 = 14.0;
/// Figures are taken after this time (s): the launch transient and the altitude hold have settled.
pub const SETTLED_AFTER_S: f64 = 6.0;
/// A flight is level when its altitude stays within this distance (m) of where the settled window
/// began, throughout the window.
pub const LEVEL_TOLERANCE_M: f64 = 0.3;
/// Width of the airspeed bins the cheapest gait is chosen in (m/s), bins centred on its multiples.
pub const SPEED_BIN_MPS: f64 = 0.5;
/// A policy's level path is this long (s): the settled window is its last 9 s.
pub const POLICY_PATH_S: f64 = 15.0;

/// The gaits flown: every combination of the listed values, the other settings the scripted gait's
/// defaults (its altitude hold chooses the flap amplitude).
#[derive(Debug, Clone, PartialEq)]
pub struct GaitFamily {
    pub frequencies_hz: Vec<f64>,
    /// The body pitch the tail holds: the trim that sets the airspeed.
    pub body_pitches_deg: Vec<f64>,
    pub pitch_amplitudes_deg: Vec<f64>,
    /// How far the wing pitch leads the flap (deg; the scripted gait's 90 is a quarter period).
    pub pitch_leads_deg: Vec<f64>,
    pub tail_trims_deg: Vec<f64>,
}

impl Default for GaitFamily {
    /// A bird's 4-6 Hz with the paper's 5.3 Hz, trims from nose-down (fast) to 25 deg nose-up (a
    /// nose held higher flies no slower), wing pitch up to 35 deg (the fast gaits feather most) leading
    /// the flap by 0 to 90 deg, and tails from up to down: 4410 gaits, the scripted gait among them.
    fn default() -> Self {
        Self {
            frequencies_hz: vec![4.0, 4.5, 5.0, 5.3, 5.6, 6.0],
            body_pitches_deg: vec![-5.0, 0.0, 5.0, 10.0, 15.0, 20.0, 25.0],
            pitch_amplitudes_deg: vec![5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0],
            pitch_leads_deg: vec![0.0, 45.0, 90.0],
            tail_trims_deg: vec![-30.0, -20.0, -10.0, 0.0, 10.0],
        }
    }
}

impl GaitFamily {
    /// Every gait of the family, frequency outermost.
    pub fn gaits(&self) -> Vec<ScriptedGaitConfig> {
        let mut gaits = Vec::new();
        for &frequency_hz in &self.frequencies_hz {
            for &body_pitch_deg in &self.body_pitches_deg {
                for &pitch_amplitude_deg in &self.pitch_amplitudes_deg {
                    for &pitch_lead_deg in &self.pitch_leads_deg {
                        for &tail_trim_deg in &self.tail_trims_deg {
                            gaits.push(ScriptedGaitConfig {
                                frequency_hz,
                                body_pitch_deg,
                                pitch_amplitude_deg,
                                pitch_lead_deg,
                                tail_trim_deg,
                                ..ScriptedGaitConfig::default()
                            });
                        }
                    }
                }
            }
        }
        gaits
    }
}

/// One gait flown, its figures over the settled window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaitFlight {
    pub gait: ScriptedGaitConfig,
    /// Flew the whole time without a simulation fault.
    pub completed: bool,
    /// Distance flown over the time (m/s): without wind, the speed through the air (the pitot
    /// airspeed reads only its body-x part, short by the cosine of the nose's pitch).
    pub speed_mps: f64,
    /// Mean absolute mechanical power into the joints (W), as the evaluation's energy counts it.
    pub power_w: f64,
    /// Absolute mechanical energy over the distance flown (J/m).
    pub energy_per_metre_j: f64,
    /// Largest distance from the window's first altitude (m).
    pub altitude_deviation_m: f64,
    /// Root mean square of the body rates' norm (p, q, r; rad/s): how much the stroke shakes the body,
    /// what the reward's r_rate prices.
    pub body_rate_rms_radps: f64,
}

impl GaitFlight {
    /// Completed and within [`LEVEL_TOLERANCE_M`] of its altitude throughout the settled window.
    pub fn level(&self) -> bool {
        self.completed && self.altitude_deviation_m <= LEVEL_TOLERANCE_M
    }

    /// The scripted gait itself (the yardstick of the energy bars), not one of its variants.
    pub fn is_scripted_gait(&self) -> bool {
        self.gait == ScriptedGaitConfig::default()
    }
}

/// Flies `gait` straight from a cruise launch, nose at its trim, for [`GAIT_FLIGHT_S`].
pub fn fly_gait(robot: &RobotModel, gait: &ScriptedGaitConfig) -> Result<GaitFlight, AnalysisError> {
    let spec = FlightSpec::cruise_launch(GAIT_FLIGHT_S, gait.body_pitch_deg);
    let log = fly(robot, &mut ScriptedGait::new(*gait), &spec)?;
    let settled: Vec<_> = log.rows().iter().filter(|r| r.state.time_s >= SETTLED_AFTER_S).collect();
    let completed = log.fault().is_none() && !settled.is_empty();
    let n = settled.len().max(1) as f64;
    let first_altitude_m = settled.first().map_or(f64::NAN, |r| r.state.position_m.z);
    let distance_m: f64 = settled.windows(2).map(|w| (w[1].state.position_m - w[0].state.position_m).length()).sum();
    let power_w = settled.iter().map(|r| r.absolute_power_w).sum::<f64>() / n;
    // The control period, from the log itself (one row per control step).
    let period_s = settled.windows(2).next().map_or(0.0, |w| w[1].state.time_s - w[0].state.time_s);
    Ok(GaitFlight {
        gait: *gait,
        completed,
        speed_mps: distance_m / (n * period_s).max(1e-9),
        power_w,
        energy_per_metre_j: power_w * n * period_s / distance_m.max(1e-9),
        altitude_deviation_m: settled
            .iter()
            .map(|r| (r.state.position_m.z - first_altitude_m).abs())
            .fold(if completed { 0.0 } else { f64::INFINITY }, f64::max),
        body_rate_rms_radps: (settled.iter().map(|r| r.state.body_rates_radps.length_squared()).sum::<f64>() / n)
            .sqrt(),
    })
}

/// The cheapest level gait (least energy per metre) of one airspeed bin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CheapestGait {
    /// The bin's centre (m/s).
    pub speed_mps: f64,
    /// Level gaits whose speed fell in the bin.
    pub level_gaits: usize,
    pub flight: GaitFlight,
}

/// Per [`SPEED_BIN_MPS`] bin of speed, the level flight that spent the least per metre, slowest first.
pub fn cheapest_by_speed(flights: &[GaitFlight]) -> Vec<CheapestGait> {
    let mut bins: Vec<CheapestGait> = Vec::new();
    for flight in flights.iter().filter(|f| f.level()) {
        let speed_mps = (flight.speed_mps / SPEED_BIN_MPS).round() * SPEED_BIN_MPS;
        match bins.iter_mut().find(|b| b.speed_mps == speed_mps) {
            Some(bin) => {
                bin.level_gaits += 1;
                if flight.energy_per_metre_j < bin.flight.energy_per_metre_j {
                    bin.flight = *flight;
                }
            }
            None => bins.push(CheapestGait { speed_mps, level_gaits: 1, flight: *flight }),
        }
    }
    bins.sort_by(|a, b| a.speed_mps.total_cmp(&b.speed_mps));
    bins
}

/// The cheapest level energy per metre at `speed_mps`, interpolated between the neighbouring bins'
/// cheapest flights (by their own speeds); `None` outside the speeds the level gaits reached.
pub fn cheapest_energy_at(cheapest: &[CheapestGait], speed_mps: f64) -> Option<f64> {
    let mut sorted: Vec<(f64, f64)> =
        cheapest.iter().map(|c| (c.flight.speed_mps, c.flight.energy_per_metre_j)).collect();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    sorted.windows(2).find(|w| w[0].0 <= speed_mps && speed_mps <= w[1].0).map(|w| {
        let (x0, y0, x1, y1) = (w[0].0, w[0].1, w[1].0, w[1].1);
        if x1 > x0 { y0 + (y1 - y0) * (speed_mps - x0) / (x1 - x0) } else { y0.min(y1) }
    })
}

/// A policy on a straight and level path at one speed, its figures over the settled window of the
/// episodes that completed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PolicyLevelFlight {
    pub label: String,
    /// The speed the path asks for (m/s).
    pub path_speed_mps: f64,
    pub episodes: usize,
    pub completed: usize,
    /// Distance flown over the time (m/s), as [`GaitFlight::speed_mps`].
    pub speed_mps: f64,
    pub power_w: f64,
    pub energy_per_metre_j: f64,
    /// Energy per metre over the cheapest level gait's at the speed flown (`None` outside the
    /// gaits' speeds).
    pub over_cheapest_gait: Option<f64>,
    /// Energy per metre over the scripted gait's in its own level flight (the energy bars' yardstick).
    pub over_scripted_gait: Option<f64>,
}

/// Flies `policy` on a level path at `speed_mps` from `episodes` randomized starts (seed `seed`).
pub fn fly_policy_level(
    robot: &RobotModel,
    policy: &FrontierPolicy,
    speed_mps: f64,
    episodes: usize,
    seed: u64,
) -> Result<PolicyLevelFlight, AnalysisError> {
    let period_s = policy.task.control_period_s(robot.timestep_s());
    let lookahead_s = policy.task.observation.lookahead_steps as f64 * period_s;
    let reference = Arc::new(level_reference(speed_mps, POLICY_PATH_S, period_s, lookahead_s));
    let controller = TrackingController::Policy(policy.policy.clone());
    let results = evaluate_tracking(robot, &controller, &policy.task, reference, episodes, seed)?;
    let settled: Vec<Vec<_>> = results
        .iter()
        .filter(|r| r.completed())
        .map(|r| r.steps.iter().filter(|s| s.time_s >= SETTLED_AFTER_S).copied().collect())
        .collect();
    let mean = |f: &dyn Fn(&[TrackingStep]) -> f64| settled.iter().map(|s| f(s)).sum::<f64>() / settled.len() as f64;
    let speed = |steps: &[TrackingStep]| {
        let distance_m: f64 = steps.windows(2).map(|w| (w[1].position_m - w[0].position_m).length()).sum();
        distance_m / (steps.len() as f64 * period_s).max(1e-9)
    };
    let power =
        |steps: &[TrackingStep]| steps.iter().map(|s| s.absolute_power_w).sum::<f64>() / steps.len().max(1) as f64;
    Ok(PolicyLevelFlight {
        label: policy.label.clone(),
        path_speed_mps: speed_mps,
        episodes,
        completed: settled.len(),
        speed_mps: mean(&speed),
        power_w: mean(&power),
        energy_per_metre_j: mean(&|steps| energy_per_metre_j(steps, period_s)),
        over_cheapest_gait: None,
        over_scripted_gait: None,
    })
}

/// Everything one run of the power curve measured.
#[derive(Debug, Clone)]
pub struct PowerCurve {
    pub gaits: Vec<GaitFlight>,
    pub cheapest: Vec<CheapestGait>,
    pub policies: Vec<PolicyLevelFlight>,
    pub episodes: usize,
    pub seed: u64,
}

impl PowerCurve {
    /// The scripted gait's own level flight, if the family holds it and it flew level.
    pub fn scripted_gait(&self) -> Option<&GaitFlight> {
        self.gaits.iter().find(|g| g.is_scripted_gait() && g.level())
    }
}

/// How the power curve is measured.
#[derive(Debug, Clone)]
pub struct PowerCurveSettings {
    pub family: GaitFamily,
    /// Speeds of the policies' level paths (m/s).
    pub policy_speeds_mps: Vec<f64>,
    pub episodes: usize,
    pub seed: u64,
}

/// The gaits are flown in this many batches, a progress call after each.
const GAIT_BATCHES: usize = 20;

/// How many gaits one batch flies, for `gaits` in all.
fn gait_batch_size(gaits: usize) -> usize {
    gaits.div_ceil(GAIT_BATCHES).max(1)
}

/// How many times [`measure_power_curve`] calls its progress callback: once per batch of gaits, once
/// per policy and speed.
pub fn step_count(settings: &PowerCurveSettings, policies: usize) -> usize {
    let gaits = settings.family.gaits().len();
    gaits.div_ceil(gait_batch_size(gaits)) + policies * settings.policy_speeds_mps.len()
}

/// Flies the gait family, then each policy at each speed; `progress` is called after each step.
pub fn measure_power_curve(
    robot: &RobotModel,
    policies: &[FrontierPolicy],
    settings: &PowerCurveSettings,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<PowerCurve, AnalysisError> {
    use rayon::prelude::*;
    let gaits = settings.family.gaits();
    let mut flights = Vec::with_capacity(gaits.len());
    for batch in gaits.chunks(gait_batch_size(gaits.len())) {
        flights.extend(batch.par_iter().map(|g| fly_gait(robot, g)).collect::<Result<Vec<_>, _>>()?);
        let level = flights.iter().filter(|f| f.level()).count();
        progress(&format!("{} of {} gaits flown, {level} level", flights.len(), gaits.len()));
    }
    let cheapest = cheapest_by_speed(&flights);
    let scripted_j_per_m = flights.iter().find(|g| g.is_scripted_gait() && g.level()).map(|g| g.energy_per_metre_j);
    let mut flown = Vec::new();
    for policy in policies {
        for &speed in &settings.policy_speeds_mps {
            let mut level = fly_policy_level(robot, policy, speed, settings.episodes, settings.seed)?;
            if level.completed > 0 {
                level.over_cheapest_gait =
                    cheapest_energy_at(&cheapest, level.speed_mps).map(|c| level.energy_per_metre_j / c);
                level.over_scripted_gait = scripted_j_per_m.map(|s| level.energy_per_metre_j / s);
            }
            progress(&format!("{} at {speed} m/s: {}/{}", policy.label, level.completed, level.episodes));
            flown.push(level);
        }
    }
    Ok(PowerCurve { gaits: flights, cheapest, policies: flown, episodes: settings.episodes, seed: settings.seed })
}

/// A row of `gaits.csv`: one gait flown.
#[derive(Serialize)]
struct GaitRow {
    frequency_hz: f64,
    body_pitch_deg: f64,
    pitch_amplitude_deg: f64,
    pitch_lead_deg: f64,
    tail_trim_deg: f64,
    scripted_gait: bool,
    level: bool,
    speed_mps: f64,
    power_w: f64,
    energy_per_metre_j: f64,
    altitude_deviation_m: f64,
    body_rate_rms_radps: f64,
}

impl GaitRow {
    fn of(f: &GaitFlight) -> Self {
        Self {
            frequency_hz: f.gait.frequency_hz,
            body_pitch_deg: f.gait.body_pitch_deg,
            pitch_amplitude_deg: f.gait.pitch_amplitude_deg,
            pitch_lead_deg: f.gait.pitch_lead_deg,
            tail_trim_deg: f.gait.tail_trim_deg,
            scripted_gait: f.is_scripted_gait(),
            level: f.level(),
            speed_mps: f.speed_mps,
            power_w: f.power_w,
            energy_per_metre_j: f.energy_per_metre_j,
            altitude_deviation_m: f.altitude_deviation_m,
            body_rate_rms_radps: f.body_rate_rms_radps,
        }
    }
}

/// A row of `power_curve.csv`: the cheapest gait of one airspeed bin (the csv crate writes no
/// flattened structs, so the gait's columns are spelled out again).
#[derive(Serialize)]
struct CheapestRow {
    speed_bin_mps: f64,
    level_gaits: usize,
    speed_mps: f64,
    power_w: f64,
    energy_per_metre_j: f64,
    frequency_hz: f64,
    body_pitch_deg: f64,
    pitch_amplitude_deg: f64,
    pitch_lead_deg: f64,
    tail_trim_deg: f64,
}

/// The files a power-curve run writes.
pub const GAITS_CSV: &str = "gaits.csv";
pub const CHEAPEST_CSV: &str = "power_curve.csv";
pub const POLICIES_CSV: &str = "policies_level.csv";
pub const POWER_CURVE_SVG: &str = "power_curve.svg";

/// Writes `gaits.csv` (every gait), `power_curve.csv` (the cheapest per bin), `policies_level.csv`
/// (when policies were flown) and `power_curve.svg` into `dir`; returns the paths written.
pub fn write_power_curve(dir: &Path, curve: &PowerCurve) -> Result<Vec<PathBuf>, AnalysisError> {
    let fail =
        |path: &Path, e: &dyn std::fmt::Display| AnalysisError::Write { path: path.to_owned(), message: e.to_string() };
    let mut written = Vec::new();
    let path = dir.join(GAITS_CSV);
    flapper_files::write_csv_records(&path, curve.gaits.iter().map(GaitRow::of)).map_err(|e| fail(&path, &e))?;
    written.push(path);
    let path = dir.join(CHEAPEST_CSV);
    let rows = curve.cheapest.iter().map(|c| CheapestRow {
        speed_bin_mps: c.speed_mps,
        level_gaits: c.level_gaits,
        speed_mps: c.flight.speed_mps,
        power_w: c.flight.power_w,
        energy_per_metre_j: c.flight.energy_per_metre_j,
        frequency_hz: c.flight.gait.frequency_hz,
        body_pitch_deg: c.flight.gait.body_pitch_deg,
        pitch_amplitude_deg: c.flight.gait.pitch_amplitude_deg,
        pitch_lead_deg: c.flight.gait.pitch_lead_deg,
        tail_trim_deg: c.flight.gait.tail_trim_deg,
    });
    flapper_files::write_csv_records(&path, rows).map_err(|e| fail(&path, &e))?;
    written.push(path);
    if !curve.policies.is_empty() {
        let path = dir.join(POLICIES_CSV);
        flapper_files::write_csv_records(&path, &curve.policies).map_err(|e| fail(&path, &e))?;
        written.push(path);
    }
    let path = dir.join(POWER_CURVE_SVG);
    draw_power_curve(&path, curve).map_err(|e| fail(&path, &e))?;
    written.push(path);
    Ok(written)
}

/// Two panels against airspeed, power and energy per metre: the cheapest level gait, the scripted gait
/// across its trims (the 5.3 Hz gait at every body pitch), and each policy across its level speeds.
fn draw_power_curve(path: &Path, curve: &PowerCurve) -> Result<(), String> {
    let scripted = ScriptedGaitConfig::default();
    let trims: Vec<&GaitFlight> = curve
        .gaits
        .iter()
        .filter(|g| g.level() && ScriptedGaitConfig { body_pitch_deg: scripted.body_pitch_deg, ..g.gait } == scripted)
        .collect();
    let mut labels: Vec<&str> = Vec::new();
    for p in &curve.policies {
        if !labels.contains(&p.label.as_str()) {
            labels.push(&p.label);
        }
    }
    let panel = |y_label: &'static str, y: fn(f64, f64) -> f64| {
        let mut curves = vec![Curve {
            label: "cheapest level gait".into(),
            points: curve
                .cheapest
                .iter()
                .map(|c| (c.flight.speed_mps, y(c.flight.power_w, c.flight.energy_per_metre_j)))
                .collect(),
            color: COLORS[2],
            dashed: false,
        }];
        let mut trim_points: Vec<(f64, f64)> =
            trims.iter().map(|g| (g.speed_mps, y(g.power_w, g.energy_per_metre_j))).collect();
        trim_points.sort_by(|a, b| a.0.total_cmp(&b.0));
        curves.push(Curve {
            label: "scripted gait, its trim swept".into(),
            points: trim_points,
            color: COLORS[2],
            dashed: true,
        });
        for (k, label) in labels.iter().enumerate() {
            let mut points: Vec<(f64, f64)> = curve
                .policies
                .iter()
                .filter(|p| p.label == *label && p.completed > 0)
                .map(|p| (p.speed_mps, y(p.power_w, p.energy_per_metre_j)))
                .collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            let color = [COLORS[0], COLORS[1], COLORS[3], COLORS[4]][k % 4];
            curves.push(Curve { label: (*label).to_owned(), points, color, dashed: false });
        }
        Panel {
            title: format!(
                "level flight: {y_label} against speed (policies: {} episodes, seed {})",
                curve.episodes, curve.seed
            ),
            x_label: "speed, no wind (m/s)",
            y_label,
            curves,
            equal_aspect: false,
        }
    };
    let panels = [
        panel("absolute mechanical power (W)", |power_w, _| power_w),
        panel("energy per metre (J/m)", |_, j_per_m| j_per_m),
    ];
    flapper_plot::draw(path, (1000, 900), &panels, (2, 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flight(speed_mps: f64, energy_per_metre_j: f64, altitude_deviation_m: f64) -> GaitFlight {
        GaitFlight {
            gait: ScriptedGaitConfig::default(),
            completed: true,
            speed_mps,
            power_w: energy_per_metre_j * speed_mps,
            energy_per_metre_j,
            altitude_deviation_m,
            body_rate_rms_radps: 0.0,
        }
    }

    #[test]
    fn the_cheapest_level_gait_of_each_bin_is_kept_and_the_sinking_ones_are_not() {
        let flights = [flight(3.1, 2.5, 0.1), flight(2.9, 2.2, 0.1), flight(3.0, 1.0, 0.9), flight(4.1, 3.0, 0.0)];
        let cheapest = cheapest_by_speed(&flights);
        assert_eq!(cheapest.len(), 2);
        assert_eq!((cheapest[0].speed_mps, cheapest[0].level_gaits), (3.0, 2));
        assert_eq!(cheapest[0].flight.energy_per_metre_j, 2.2, "the sinking 1.0 J/m flight is not level");
        assert_eq!(cheapest[1].speed_mps, 4.0);
    }

    #[test]
    fn the_cheapest_energy_is_interpolated_between_airspeeds_and_absent_outside() {
        let cheapest = cheapest_by_speed(&[flight(3.0, 2.0, 0.0), flight(5.0, 4.0, 0.0)]);
        assert_eq!(cheapest_energy_at(&cheapest, 4.0), Some(3.0));
        assert_eq!(cheapest_energy_at(&cheapest, 3.0), Some(2.0));
        assert_eq!(cheapest_energy_at(&cheapest, 5.5), None);
        assert_eq!(cheapest_energy_at(&cheapest, 2.0), None);
    }

    #[test]
    fn the_default_family_holds_the_scripted_gait_once() {
        let gaits = GaitFamily::default().gaits();
        assert_eq!(gaits.len(), 6 * 7 * 7 * 3 * 5);
        assert_eq!(gaits.iter().filter(|g| **g == ScriptedGaitConfig::default()).count(), 1);
    }
}
