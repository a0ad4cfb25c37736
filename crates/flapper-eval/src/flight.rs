//! Flying a controller through the control loop and recording every control step.

use flapper_sim::{InitialState, ModelError, RobotModel, Simulator, Vec3, quat_from_euler};
use flapper_task::{ControlConfig, ControlLoop};

use crate::controller::{Controller, FlightState};
use crate::flight_log::{FlightLog, FlightRow};

/// How long to fly and from where.
#[derive(Debug, Clone, Copy)]
pub struct FlightSpec {
    pub seconds: f64,
    pub initial: InitialState,
    pub control: ControlConfig,
}

impl FlightSpec {
    /// Level cruise launch: 3.8 m/s forward at 10 m altitude, nose up `pitch_deg`.
    pub fn cruise_launch(seconds: f64, pitch_deg: f64) -> Self {
        Self {
            seconds,
            initial: InitialState {
                position_m: Vec3::new(0.0, 0.0, 10.0),
                orientation: quat_from_euler(0.0, pitch_deg.to_radians(), 0.0),
                linear_velocity_mps: Vec3::new(flapper_sim::CRUISE_SPEED_MPS, 0.0, 0.0),
                ..InitialState::default()
            },
            control: ControlConfig::default(),
        }
    }
}

/// Flies `controller` for `spec.seconds` (or until the simulation faults) and logs each control step.
pub fn fly(robot: &RobotModel, controller: &mut dyn Controller, spec: &FlightSpec) -> Result<FlightLog, ModelError> {
    Ok(fly_simulator(robot.instantiate()?, controller, spec))
}

/// As [`fly`], with a simulator prepared by the caller (edited masses, wind, fluid coefficients...).
pub fn fly_simulator(sim: Simulator, controller: &mut dyn Controller, spec: &FlightSpec) -> FlightLog {
    let mut control = ControlLoop::new(sim, spec.control);
    control.reset(&spec.initial);
    controller.reset();
    let steps = (spec.seconds / control.control_period_s()).round() as usize;
    let mut log = FlightLog::with_capacity(steps + 1);
    let mut state = FlightState::read(control.sim());
    for _ in 0..steps {
        let targets = controller.joint_targets(&state);
        // Log the state the decision was made on, with the decision.
        let result = control.step(&targets);
        log.push(FlightRow::after_step(&state, &control));
        if let Err(fault) = result {
            log.set_fault(fault);
            break;
        }
        state = FlightState::read(control.sim());
    }
    log
}
