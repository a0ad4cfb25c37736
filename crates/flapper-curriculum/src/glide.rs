//! The glide bar of a gate: `flapper modes`' flight along the longitudinal reference with a
//! checkpoint, and the share of its glide segment flown with the wings held (paper: the energy term
//! makes the robot glide "instead of flapping when possible, mimicking physical birds").
//!
//! The validation set cannot see this: a checkpoint that tracks the glide segment while flapping
//! scores as well as one that glides it. One 24 s flight from the exact start, so every validation
//! can afford it.

use std::path::Path;
use std::sync::Arc;

use flapper_analysis::AnalysisError;
use flapper_analysis::modes::measure_flight_modes;
use flapper_eval::load_flight_policy;
use flapper_sim::RobotModel;

use crate::validation::ValidationError;

/// The share (0 to 1) of the longitudinal reference's glide segment that the checkpoint flies with its
/// wings held; NaN where it does not fly the reference to its end.
pub fn glide_fraction(robot: &RobotModel, checkpoint: &Path) -> Result<f64, ValidationError> {
    let (policy, task) = load_flight_policy(checkpoint)?;
    match measure_flight_modes(robot, Arc::new(policy), &task) {
        Ok(modes) => Ok(modes.glide_segment_fraction()),
        Err(AnalysisError::FlightFailed { .. }) => Ok(f64::NAN),
        Err(e) => Err(ValidationError::FlightModes(e.to_string())),
    }
}

/// Whether a measured glide fraction reaches `bar`; a checkpoint not measured (`None`) or that did
/// not fly the reference (NaN) never does.
pub fn meets_glide_bar(glide_fraction: Option<f64>, bar: f64) -> bool {
    glide_fraction.is_some_and(|share| share >= bar)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_share_must_reach_the_bar_and_a_failed_flight_never_does() {
        assert!(meets_glide_bar(Some(0.5), 0.5) && meets_glide_bar(Some(0.74), 0.5));
        assert!(!meets_glide_bar(Some(0.49), 0.5));
        assert!(!meets_glide_bar(Some(f64::NAN), 0.0), "the reference not flown to its end");
        assert!(!meets_glide_bar(None, 0.0), "not measured");
    }
}
