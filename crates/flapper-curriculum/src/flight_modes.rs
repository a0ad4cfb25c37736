//! The flight-mode bars of a gate: `flapper modes`' flight along the longitudinal reference with a
//! checkpoint, and what it says about the paper's efficient bird: the share of the glide segment flown
//! with the wings held ("gliding instead of flapping when possible, mimicking physical birds"), the
//! energy per metre of the whole flight against the scripted gait's on the same start, and the flap's
//! fundamental in the cruise segment (the paper: 4-6 Hz, 5.3 Hz in its cruise).
//!
//! The validation set cannot see these: a checkpoint that tracks the glide segment while flapping
//! scores as well as one that glides it, and the cheapest of two equally precise checkpoints is not
//! preferred. One 24 s flight from the exact start (and the scripted gait's once; the cruise
//! reference's 30 s more where the gate reads the flap frequency there), so every validation can
//! afford it. Energy and frequency swing between neighbouring checkpoints as the glide does, so a
//! stage that must hand over an efficient controller selects on them here rather than hoping the last
//! checkpoint is one.

use std::path::Path;
use std::sync::Arc;

use flapper_analysis::AnalysisError;
use flapper_analysis::frontier;
use flapper_analysis::modes::{SEGMENTS, longitudinal_from_exact_start, measure_flight_modes, named_from_exact_start};
use flapper_eval::ScriptedGaitConfig;
use flapper_eval::load_flight_policy;
use flapper_eval::tracking::TrackingController;
use flapper_ppo::ActorCritic;
use flapper_sim::{ActuatedJoint, RobotModel};
use flapper_task::TaskConfig;

use crate::config::{CruiseFlapFlight, Gate};
use crate::validation::{Score, ValidationError};

/// What one flight along the longitudinal reference says of a checkpoint's flight modes; NaN where the
/// checkpoint does not fly the reference to its end.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModeFigures {
    /// The share (0 to 1) of the glide segment flown with the wings held.
    pub glide_fraction: f64,
    /// Energy per metre over the whole reference, over the scripted gait's from the same start.
    pub energy_ratio: f64,
    /// The flap's fundamental frequency in the cruise segment (Hz).
    pub cruise_flap_hz: f64,
}

impl ModeFigures {
    pub const NOT_FLOWN: Self = Self { glide_fraction: f64::NAN, energy_ratio: f64::NAN, cruise_flap_hz: f64::NAN };
}

/// Flies the longitudinal reference from its exact start with the checkpoint and with the scripted gait;
/// the flap frequency from that flight's cruise segment or from a flight of the cruise reference, as
/// `flap_flight` says.
pub fn flight_mode_figures(
    robot: &RobotModel,
    checkpoint: &Path,
    flap_flight: CruiseFlapFlight,
) -> Result<ModeFigures, ValidationError> {
    let (policy, task) = load_flight_policy(checkpoint)?;
    let policy = Arc::new(policy);
    let period_s = task.control_period_s(robot.timestep_s());
    let modes = match measure_flight_modes(robot, Arc::clone(&policy), &task) {
        Ok(modes) => modes,
        Err(AnalysisError::FlightFailed { .. }) => return Ok(ModeFigures::NOT_FLOWN),
        Err(e) => return Err(ValidationError::FlightModes(e.to_string())),
    };
    // As `flapper eval` compares: the scripted gait's energy per metre over what it flies (it falls behind
    // in the climb, about 9 s in).
    let scripted =
        longitudinal_from_exact_start(robot, &TrackingController::Scripted(ScriptedGaitConfig::default()), &task)
            .map_err(|e| ValidationError::FlightModes(format!("the scripted gait, for the energy ratio: {e}")))?;
    let own = flapper_eval::tracking::energy_per_metre_j(&modes.steps, period_s);
    // The ratio as `flapper frontier` takes it; NaN (no bar met) where the scripted gait flew no energy.
    let energy_ratio = frontier::energy_ratio(own, scripted.energy_per_metre_j(period_s)).unwrap_or(f64::NAN);
    let cruise_flap_hz = match flap_flight {
        // The validation's starts are read by the validation itself (`ValidationSet::read_flap_on`).
        CruiseFlapFlight::LongitudinalSegment | CruiseFlapFlight::ValidationStarts => {
            let cruise = SEGMENTS.iter().position(|(name, _, _)| *name == "cruise").expect("the first segment");
            modes.report.segments[cruise].flap_fundamental_hz
        }
        CruiseFlapFlight::CruiseReference => cruise_reference_flap_hz(robot, policy, &task, period_s)?,
    };
    Ok(ModeFigures { glide_fraction: modes.glide_segment_fraction(), energy_ratio, cruise_flap_hz })
}

/// The flap's fundamental over the cruise reference flown from its exact start (after its first
/// second, as `flapper eval`'s table); NaN where the flight does not reach the reference's end.
fn cruise_reference_flap_hz(
    robot: &RobotModel,
    policy: Arc<ActorCritic>,
    task: &TaskConfig,
    period_s: f64,
) -> Result<f64, ValidationError> {
    let flight = named_from_exact_start(robot, &TrackingController::Policy(policy), task, "cruise")
        .map_err(|e| ValidationError::FlightModes(format!("the cruise reference, for the flap frequency: {e}")))?;
    if !flight.completed() {
        return Ok(f64::NAN);
    }
    Ok(flight.fundamental(ActuatedJoint::FlapLeft, period_s).map_or(f64::NAN, |f| f.frequency_hz))
}

/// Whether the gate has any flight-mode bar (then every validation measures [`ModeFigures`]).
pub fn gate_asks_flight_modes(gate: &Gate) -> bool {
    gate.glide_fraction.is_some()
        || gate.max_energy_ratio.is_some()
        || gate.cruise_flap_hz.is_some()
        || !gate.reference_max_energy_ratio.is_empty()
}

/// Whether measured figures, and the validation's energy ratios in `score`, meet the gate's flight-mode
/// bars; a checkpoint not measured (`None`) or that did not fly the reference (NaN) meets none.
pub fn meets_flight_mode_bars(gate: &Gate, figures: Option<&ModeFigures>, score: &Score) -> bool {
    if !gate_asks_flight_modes(gate) {
        return true;
    }
    let Some(f) = figures else { return false };
    flight_mode_verdicts(gate, f, score).all(|met| met != Some(false))
}

/// How many of the gate's flight-mode bars are met (none where unmeasured).
pub fn flight_mode_bars_met(gate: &Gate, figures: Option<&ModeFigures>, score: &Score) -> usize {
    figures.map_or(0, |f| flight_mode_verdicts(gate, f, score).filter(|&met| met == Some(true)).count())
}

/// Each flight-mode bar, met or not (`None`: the gate does not ask it): the glide, the energy, the flap
/// frequency, then each priced validation entry's energy ratio (an entry without one meets no bar).
fn flight_mode_verdicts<'a>(
    gate: &'a Gate,
    f: &ModeFigures,
    score: &'a Score,
) -> impl Iterator<Item = Option<bool>> + 'a {
    let flight = [
        gate.glide_fraction.map(|bar| f.glide_fraction >= bar),
        gate.max_energy_ratio.map(|bar| f.energy_ratio <= bar),
        gate.cruise_flap_hz.map(|[low, high]| (low..=high).contains(&f.cruise_flap_hz)),
    ];
    let entries = gate
        .reference_max_energy_ratio
        .iter()
        .map(|(name, bar)| Some(score.energy_ratio(name).is_some_and(|ratio| ratio <= *bar)));
    flight.into_iter().chain(entries)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validation::ReferenceScore;

    fn figures(glide_fraction: f64, energy_ratio: f64, cruise_flap_hz: f64) -> Option<ModeFigures> {
        Some(ModeFigures { glide_fraction, energy_ratio, cruise_flap_hz })
    }

    /// A validation score with these entries' energy ratios (`None`: not priced).
    fn flown(entries: &[(&str, Option<f64>)]) -> Score {
        let references = entries
            .iter()
            .map(|&(name, energy_ratio)| ReferenceScore { energy_ratio, ..ReferenceScore::flown(name, 50, 50, 0.2) })
            .collect();
        Score { completed_percent: 100.0, mean_rms_m: 0.2, references }
    }

    #[test]
    fn each_bar_must_be_met_and_a_failed_or_unmeasured_flight_meets_none() {
        let unpriced = flown(&[("longitudinal", None)]);
        let glide = Gate { glide_fraction: Some(0.5), ..Gate::completing(0.0) };
        assert!(meets_flight_mode_bars(&glide, figures(0.5, 9.0, 7.0).as_ref(), &unpriced));
        assert!(meets_flight_mode_bars(&glide, figures(0.74, 1.0, 5.0).as_ref(), &unpriced));
        assert!(!meets_flight_mode_bars(&glide, figures(0.49, 1.0, 5.0).as_ref(), &unpriced));
        assert!(
            !meets_flight_mode_bars(&glide, Some(&ModeFigures::NOT_FLOWN), &unpriced),
            "the reference not flown to its end"
        );
        assert!(!meets_flight_mode_bars(&glide, None, &unpriced), "not measured");
        let energy = Gate { max_energy_ratio: Some(1.5), ..Gate::completing(0.0) };
        assert!(meets_flight_mode_bars(&energy, figures(0.0, 1.5, 7.0).as_ref(), &unpriced));
        assert!(!meets_flight_mode_bars(&energy, figures(0.9, 1.51, 5.3).as_ref(), &unpriced));
        let frequency = Gate { cruise_flap_hz: Some([4.0, 6.0]), ..Gate::completing(0.0) };
        assert!(meets_flight_mode_bars(&frequency, figures(0.0, 9.0, 5.3).as_ref(), &unpriced));
        assert!(!meets_flight_mode_bars(&frequency, figures(0.9, 1.0, 6.32).as_ref(), &unpriced));
        assert!(!meets_flight_mode_bars(&frequency, figures(0.9, 1.0, 3.9).as_ref(), &unpriced));
        let none = Gate::completing(0.0);
        assert!(meets_flight_mode_bars(&none, None, &unpriced), "a gate without flight-mode bars asks nothing");
    }

    #[test]
    fn each_priced_entry_must_be_within_its_energy_bar_and_counts_as_one_bar() {
        let gate = Gate {
            reference_max_energy_ratio: [("longitudinal".to_owned(), 1.5), ("immelmann".to_owned(), 3.0)].into(),
            cruise_flap_hz: Some([4.0, 6.0]),
            ..Gate::completing(0.0)
        };
        assert!(gate_asks_flight_modes(&gate));
        let at_5hz = figures(0.0, 9.0, 5.0);
        let cheap = flown(&[("longitudinal", Some(1.5)), ("immelmann", Some(2.9))]);
        assert!(meets_flight_mode_bars(&gate, at_5hz.as_ref(), &cheap), "each at or under its bar");
        assert_eq!(flight_mode_bars_met(&gate, at_5hz.as_ref(), &cheap), 3);
        let costly_immelmann = flown(&[("longitudinal", Some(1.4)), ("immelmann", Some(3.11))]);
        assert!(!meets_flight_mode_bars(&gate, at_5hz.as_ref(), &costly_immelmann), "3.11 x over its 3 x");
        assert_eq!(flight_mode_bars_met(&gate, at_5hz.as_ref(), &costly_immelmann), 2);
        let unpriced = flown(&[("longitudinal", Some(1.4)), ("immelmann", None)]);
        assert!(!meets_flight_mode_bars(&gate, at_5hz.as_ref(), &unpriced), "an entry without a ratio meets no bar");
        let scripted_flew_nothing = flown(&[("longitudinal", Some(1.4)), ("immelmann", Some(f64::NAN))]);
        assert!(!meets_flight_mode_bars(&gate, at_5hz.as_ref(), &scripted_flew_nothing), "NaN meets no bar");
        assert!(!meets_flight_mode_bars(&gate, None, &cheap), "not measured");
    }
}
