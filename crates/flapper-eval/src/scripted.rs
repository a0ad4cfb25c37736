//! The scripted baseline: a fixed 5.3 Hz flapping gait with simple feedback. It proves the model can
//! fly before any learning and stays as the controller a learned policy is compared against.
//!
//! - flap: `A sin(2 pi f t)` on both wings, the amplitude A raised when the robot is below its
//!   starting altitude or sinking (altitude hold through thrust and lift);
//! - wing pitch: `P sin(2 pi f t + lead)`, leading the flap by 90 deg, plus a differential term on
//!   roll and roll rate (this model damps a roll disturbance even without it, see README);
//! - tail: trim plus feedback on body pitch and pitch rate (holds the flight attitude).

use flapper_sim::N_ACTUATED_JOINTS;

use crate::controller::{Controller, FlightState};

/// Gains and gait shape. Angles in degrees where the name says `_deg`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScriptedGaitConfig {
    pub frequency_hz: f64,
    /// Flap target amplitude before the 7 Hz filter (about 16 deg reaches the joint at 5.3 Hz).
    pub flap_amplitude_deg: f64,
    pub pitch_amplitude_deg: f64,
    /// Phase by which wing pitch leads flap.
    pub pitch_lead_deg: f64,
    pub tail_trim_deg: f64,
    /// Body pitch (nose up) the tail holds.
    pub body_pitch_deg: f64,
    /// Tail deflection per radian of body-pitch error.
    pub pitch_gain: f64,
    /// Tail deflection (rad) per rad/s of pitch rate.
    pub pitch_rate_gain: f64,
    /// Differential wing pitch (rad) per radian of roll.
    pub roll_gain: f64,
    /// Differential wing pitch (rad) per rad/s of roll rate.
    pub roll_rate_gain: f64,
    /// Extra flap amplitude (deg) per metre below the starting altitude.
    pub altitude_gain_deg_per_m: f64,
    /// Extra flap amplitude (deg) per m/s of sink rate.
    pub climb_rate_gain_deg_per_mps: f64,
    pub max_flap_amplitude_deg: f64,
}

impl Default for ScriptedGaitConfig {
    fn default() -> Self {
        Self {
            frequency_hz: 5.3,
            flap_amplitude_deg: 20.0,
            pitch_amplitude_deg: 10.0,
            pitch_lead_deg: 90.0,
            tail_trim_deg: -20.0,
            body_pitch_deg: 20.0,
            pitch_gain: 0.3,
            pitch_rate_gain: 0.05,
            roll_gain: 0.5,
            roll_rate_gain: 0.05,
            altitude_gain_deg_per_m: 10.0,
            climb_rate_gain_deg_per_mps: 2.0,
            max_flap_amplitude_deg: 40.0,
        }
    }
}

/// The scripted gait; holds the altitude it started at.
#[derive(Debug, Clone)]
pub struct ScriptedGait {
    config: ScriptedGaitConfig,
    reference_altitude_m: Option<f64>,
}

impl ScriptedGait {
    pub fn new(config: ScriptedGaitConfig) -> Self {
        Self { config, reference_altitude_m: None }
    }

    pub fn config(&self) -> &ScriptedGaitConfig {
        &self.config
    }

    /// Holds `altitude_m` from now on instead of the starting altitude (to follow a reference).
    pub fn set_altitude_target(&mut self, altitude_m: f64) {
        self.reference_altitude_m = Some(altitude_m);
    }
}

impl Controller for ScriptedGait {
    fn reset(&mut self) {
        self.reference_altitude_m = None;
    }

    fn joint_targets(&mut self, state: &FlightState) -> [f64; N_ACTUATED_JOINTS] {
        let c = &self.config;
        let reference_altitude = *self.reference_altitude_m.get_or_insert(state.position_m.z);
        let altitude_error = state.position_m.z - reference_altitude;
        let amplitude_deg = (c.flap_amplitude_deg
            - c.altitude_gain_deg_per_m * altitude_error
            - c.climb_rate_gain_deg_per_mps * state.velocity_mps.z)
            .clamp(0.0, c.max_flap_amplitude_deg);
        let phase = std::f64::consts::TAU * c.frequency_hz * state.time_s;
        let flap = amplitude_deg.to_radians() * phase.sin();
        let pitch = c.pitch_amplitude_deg.to_radians() * (phase + c.pitch_lead_deg.to_radians()).sin();

        let [roll, body_pitch, _] = state.euler_rad;
        let (roll_rate, pitch_rate_nose_down) = (state.body_rates_radps.x, state.body_rates_radps.y);
        // Roll right (right wing down): pitch the right wing up (negative) for more lift there.
        let differential = c.roll_gain * roll + c.roll_rate_gain * roll_rate;
        // Nose below the reference: tail trailing edge up (negative) to pitch up.
        let tail = c.tail_trim_deg.to_radians()
            - c.pitch_gain * (c.body_pitch_deg.to_radians() - body_pitch)
            - c.pitch_rate_gain * pitch_rate_nose_down;
        [flap, pitch + differential, flap, pitch - differential, tail]
    }
}
