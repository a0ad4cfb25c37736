//! What a controller sees and decides at each 50 Hz control step, and the simplest controller.

use flapper_sim::{N_ACTUATED_JOINTS, Quat, Simulator, Vec3, quat_to_euler};

/// The robot's state as a controller sees it at a control step.
#[derive(Debug, Clone, Copy)]
pub struct FlightState {
    pub time_s: f64,
    pub position_m: Vec3,
    pub orientation: Quat,
    /// Roll, pitch (nose up positive), yaw.
    pub euler_rad: [f64; 3],
    pub velocity_mps: Vec3,
    /// Body-frame p, q, r.
    pub body_rates_radps: Vec3,
    pub airspeed_mps: f64,
    pub joint_positions_rad: [f64; N_ACTUATED_JOINTS],
    pub joint_velocities_radps: [f64; N_ACTUATED_JOINTS],
}

impl FlightState {
    pub fn read(sim: &Simulator) -> Self {
        let orientation = sim.orientation();
        Self {
            time_s: sim.time_s(),
            position_m: sim.base_position_m(),
            orientation,
            euler_rad: quat_to_euler(orientation),
            velocity_mps: sim.linear_velocity_mps(),
            body_rates_radps: sim.body_rates(),
            airspeed_mps: sim.pitot_airspeed_mps(),
            joint_positions_rad: sim.joint_positions(),
            joint_velocities_radps: sim.joint_velocities(),
        }
    }
}

/// Decides the five joint targets (radians, order q1..q5) once per control step.
pub trait Controller {
    fn joint_targets(&mut self, state: &FlightState) -> [f64; N_ACTUATED_JOINTS];
    /// Clears any internal state before a new flight.
    fn reset(&mut self) {}
}

/// Wings held flat, tail at a fixed angle: an unpowered glide.
#[derive(Debug, Clone, Copy)]
pub struct GlideController {
    pub tail_rad: f64,
}

impl Controller for GlideController {
    fn joint_targets(&mut self, _state: &FlightState) -> [f64; N_ACTUATED_JOINTS] {
        [0.0, 0.0, 0.0, 0.0, self.tail_rad]
    }
}
