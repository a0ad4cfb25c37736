//! The paper's control loop (III-A): joint targets decided at 50 Hz, low-pass filtered at the
//! 250 Hz simulation rate, applied to the joints' PD servos for 5 substeps.

use flapper_sim::{InitialState, ModelError, N_ACTUATED_JOINTS, SimFault, Simulator};
use serde::{Deserialize, Serialize};

use crate::action_filter::LowPassFilter;
use crate::config::ControlConfig;

/// A simulator driven through the filter at the control rate.
pub struct ControlLoop {
    sim: Simulator,
    filter: LowPassFilter,
    /// Its substeps and filter cutoff (the action scale belongs to the task's action map).
    config: ControlConfig,
    commanded: [f64; N_ACTUATED_JOINTS],
    last_step_work: JointWork,
}

/// Work the actuators did on the joints during one control step, integrated at the simulation rate.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct JointWork {
    /// Integral of sum(torque * joint velocity): positive work minus work absorbed (J).
    pub net_j: f64,
    /// Integral of sum(|torque * joint velocity|): every joule the motors move, either way (J).
    pub absolute_j: f64,
}

/// Everything a control loop carries from one step to the next (for exact checkpoints).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ControlLoopState {
    /// MuJoCo's integration state ([`Simulator::physics_state`]).
    pub physics: Vec<f64>,
    /// The filter's output, one per joint (rad).
    pub filter_rad: [f64; N_ACTUATED_JOINTS],
    pub commanded_rad: [f64; N_ACTUATED_JOINTS],
    pub last_step_work: JointWork,
}

impl ControlLoop {
    pub fn new(sim: Simulator, config: ControlConfig) -> Self {
        let filter = LowPassFilter::new(config.filter_cutoff_hz, sim.timestep_s());
        let mut control =
            Self { sim, filter, config, commanded: [0.0; N_ACTUATED_JOINTS], last_step_work: JointWork::default() };
        control.reset(&InitialState::default());
        control
    }

    /// Resets the simulation; the filter starts at the initial joint positions.
    pub fn reset(&mut self, initial: &InitialState) {
        self.sim.reset(initial);
        self.filter.reset(initial.joint_positions_rad);
        self.commanded = initial.joint_positions_rad;
    }

    /// Applies one control decision (joint targets in radians, order q1..q5) for one control period.
    pub fn step(&mut self, targets_rad: &[f64; N_ACTUATED_JOINTS]) -> Result<(), SimFault> {
        self.commanded = *targets_rad;
        let dt = self.sim.timestep_s();
        let mut work = JointWork::default();
        for _ in 0..self.config.substeps {
            let filtered = self.filter.update(targets_rad);
            self.sim.set_joint_targets(&filtered);
            self.sim.step(1)?;
            let (torques, velocities) = (self.sim.actuator_torques(), self.sim.joint_velocities());
            for (torque, velocity) in torques.iter().zip(velocities) {
                work.net_j += torque * velocity * dt;
                work.absolute_j += (torque * velocity).abs() * dt;
            }
        }
        self.last_step_work = work;
        Ok(())
    }

    /// The loop's state, to continue later with [`ControlLoop::restore`].
    pub fn state(&self) -> ControlLoopState {
        ControlLoopState {
            physics: self.sim.physics_state(),
            filter_rad: self.filter.output(),
            commanded_rad: self.commanded,
            last_step_work: self.last_step_work,
        }
    }

    /// Continues from a state taken by [`ControlLoop::state`] on a loop with the same model.
    pub fn restore(&mut self, state: &ControlLoopState) -> Result<(), ModelError> {
        self.sim.set_physics_state(&state.physics)?;
        self.filter.reset(state.filter_rad);
        self.commanded = state.commanded_rad;
        self.last_step_work = state.last_step_work;
        Ok(())
    }

    /// Seconds of simulated time per control decision (0.02 s).
    pub fn control_period_s(&self) -> f64 {
        self.config.substeps as f64 * self.sim.timestep_s()
    }

    /// Work done on the joints during the last control step.
    pub fn last_step_work(&self) -> JointWork {
        self.last_step_work
    }

    /// The last targets the controller asked for (before the filter).
    pub fn commanded_targets(&self) -> [f64; N_ACTUATED_JOINTS] {
        self.commanded
    }

    pub fn sim(&self) -> &Simulator {
        &self.sim
    }

    pub fn sim_mut(&mut self) -> &mut Simulator {
        &mut self.sim
    }
}
