//! How an episode ends (paper III-F). Termination (the policy failed: no bootstrap) is kept apart
//! from truncation (time ran out or the simulation broke: the learner bootstraps the value).

use crate::config::EpisodeConfig;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EpisodeEnd {
    /// More than `max_position_error_m` from the current target (terminated).
    TooFarFromTarget,
    /// |roll| or |pitch| beyond the limit in stages 1-2 (terminated).
    AttitudeLimit,
    /// `max_steps` reached (truncated).
    TimeLimit,
    /// A fixed reference ran out (truncated).
    ReferenceEnd,
    /// MuJoCo warned or the state stopped being finite (truncated, counted apart).
    SimulationFault,
}

impl EpisodeEnd {
    pub const ALL: [EpisodeEnd; 5] =
        [Self::TooFarFromTarget, Self::AttitudeLimit, Self::TimeLimit, Self::ReferenceEnd, Self::SimulationFault];

    /// Terminated (a failure of the policy) rather than truncated.
    pub fn is_termination(self) -> bool {
        matches!(self, Self::TooFarFromTarget | Self::AttitudeLimit)
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::TooFarFromTarget => "too_far",
            Self::AttitudeLimit => "attitude",
            Self::TimeLimit => "time_limit",
            Self::ReferenceEnd => "reference_end",
            Self::SimulationFault => "sim_fault",
        }
    }
}

/// The failure conditions, checked after every control step.
pub fn check_failure(
    config: &EpisodeConfig,
    position_error_m: f64,
    roll_rad: f64,
    pitch_rad: f64,
) -> Option<EpisodeEnd> {
    if !(position_error_m <= config.max_position_error_m) {
        return Some(EpisodeEnd::TooFarFromTarget);
    }
    let limit = config.attitude_limit_deg.to_radians();
    if config.attitude_termination && (roll_rad.abs() > limit || pitch_rad.abs() > limit) {
        return Some(EpisodeEnd::AttitudeLimit);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_metres_from_target_terminates() {
        let c = EpisodeConfig::default();
        assert_eq!(check_failure(&c, 2.99, 0.0, 0.0), None);
        assert_eq!(check_failure(&c, 3.01, 0.0, 0.0), Some(EpisodeEnd::TooFarFromTarget));
        assert_eq!(check_failure(&c, f64::NAN, 0.0, 0.0), Some(EpisodeEnd::TooFarFromTarget));
        assert!(EpisodeEnd::TooFarFromTarget.is_termination());
    }

    #[test]
    fn attitude_limit_only_when_switched_on() {
        let on = EpisodeConfig::default();
        let off = EpisodeConfig { attitude_termination: false, ..on.clone() };
        let steep = 91f64.to_radians();
        assert_eq!(check_failure(&on, 0.0, steep, 0.0), Some(EpisodeEnd::AttitudeLimit));
        assert_eq!(check_failure(&on, 0.0, 0.0, -steep), Some(EpisodeEnd::AttitudeLimit));
        assert_eq!(check_failure(&on, 0.0, 89f64.to_radians(), 0.0), None);
        assert_eq!(check_failure(&off, 0.0, steep, steep), None);
    }

    #[test]
    fn time_limit_and_faults_are_truncations() {
        for end in [EpisodeEnd::TimeLimit, EpisodeEnd::ReferenceEnd, EpisodeEnd::SimulationFault] {
            assert!(!end.is_termination());
        }
    }
}
