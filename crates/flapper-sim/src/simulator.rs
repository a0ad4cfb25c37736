//! One simulation instance: reset, drive, step, read and edit. Each environment owns one.

use std::sync::Arc;

use mujoco_rs::prelude::*;

use crate::error::{ModelError, SimFault};
use crate::geometry::{Quat, Vec3, quat_from_wxyz, quat_rotate_inverse, quat_to_wxyz};
use crate::model::{Layout, RobotModel};
use crate::robot::{ActuatedJoint, BODY_NAMES, LIFTING_SURFACE_GEOMS, N_ACTUATED_JOINTS};

/// Where an episode starts. Velocities: linear in the world frame, angular in the body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InitialState {
    pub position_m: Vec3,
    pub orientation: Quat,
    pub linear_velocity_mps: Vec3,
    /// Body-frame angular rates p, q, r.
    pub body_rates_radps: Vec3,
    pub joint_positions_rad: [f64; N_ACTUATED_JOINTS],
    pub joint_velocities_radps: [f64; N_ACTUATED_JOINTS],
}

impl Default for InitialState {
    /// At the origin, level, at rest, joints at the nominal pose (wings and tail flat).
    fn default() -> Self {
        Self {
            position_m: Vec3::ZERO,
            orientation: Quat::IDENTITY,
            linear_velocity_mps: Vec3::ZERO,
            body_rates_radps: Vec3::ZERO,
            joint_positions_rad: [0.0; N_ACTUATED_JOINTS],
            joint_velocities_radps: [0.0; N_ACTUATED_JOINTS],
        }
    }
}

/// The five coefficients of MuJoCo's ellipsoid fluid model (paper Table II).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FluidCoefficients {
    pub blunt_drag: f64,
    pub slender_drag: f64,
    pub angular_drag: f64,
    pub kutta_lift: f64,
    pub magnus_lift: f64,
}

impl FluidCoefficients {
    pub fn to_array(self) -> [f64; 5] {
        [self.blunt_drag, self.slender_drag, self.angular_drag, self.kutta_lift, self.magnus_lift]
    }

    pub fn from_array(c: [f64; 5]) -> Self {
        Self { blunt_drag: c[0], slender_drag: c[1], angular_drag: c[2], kutta_lift: c[3], magnus_lift: c[4] }
    }
}

/// `geom_fluid` layout: [flag, 5 coefficients, virtual mass x3, virtual inertia x3].
const FLUID_COEFFICIENTS: std::ops::Range<usize> = 1..6;
const FLUID_ADDED_MASS: std::ops::Range<usize> = 6..9;
const FLUID_ADDED_INERTIA: std::ops::Range<usize> = 9..12;

/// A MuJoCo instance of the robot with its own model copy.
pub struct Simulator {
    data: MjData<Box<MjModel>>,
    layout: Arc<Layout>,
    nominal: RobotModel,
    /// Mass or inertia was edited: MuJoCo's derived constants are recomputed at the next reset.
    constants_stale: bool,
}

impl RobotModel {
    /// A new simulation instance with its own copy of the model (so per-instance edits such as wind
    /// or masses do not leak between environments), reset to the default initial state.
    pub fn instantiate(&self) -> Result<Simulator, ModelError> {
        Simulator::new(self)
    }
}

impl Simulator {
    fn new(robot: &RobotModel) -> Result<Self, ModelError> {
        let model = robot.mujoco().clone();
        let data = MjData::try_new(Box::new(model))
            .map_err(|e| ModelError::Load { origin: robot.origin().to_owned(), message: e.to_string() })?;
        let mut sim = Self { data, layout: robot.layout().clone(), nominal: robot.clone(), constants_stale: false };
        sim.reset(&InitialState::default());
        Ok(sim)
    }

    /// Sets time to zero and the state to `initial`; joint targets start at the joint positions.
    /// Clears MuJoCo's warnings. Parameter edits made since the last reset take effect here.
    pub fn reset(&mut self, initial: &InitialState) {
        if self.constants_stale {
            self.data.set_const();
            self.constants_stale = false;
        }
        self.data.reset();
        let l = &*self.layout;
        let qpos = self.data.qpos_mut();
        qpos[l.base_qpos..l.base_qpos + 3].copy_from_slice(&initial.position_m.to_array());
        qpos[l.base_qpos + 3..l.base_qpos + 7].copy_from_slice(&quat_to_wxyz(initial.orientation.normalize()));
        for (i, &adr) in l.joint_qpos.iter().enumerate() {
            qpos[adr] = initial.joint_positions_rad[i];
        }
        let qvel = self.data.qvel_mut();
        qvel[l.base_dof..l.base_dof + 3].copy_from_slice(&initial.linear_velocity_mps.to_array());
        qvel[l.base_dof + 3..l.base_dof + 6].copy_from_slice(&initial.body_rates_radps.to_array());
        for (i, &adr) in l.joint_dof.iter().enumerate() {
            qvel[adr] = initial.joint_velocities_radps[i];
        }
        let ctrl = self.data.ctrl_mut();
        for (i, &id) in l.actuator_ids.iter().enumerate() {
            ctrl[id] = initial.joint_positions_rad[i];
        }
        self.data.forward();
    }

    /// MuJoCo's full integration state (time, positions, velocities, controls, warm start, applied
    /// forces): everything the next step depends on besides the model. With
    /// [`Simulator::set_physics_state`] a run continues bit for bit (training checkpoints).
    pub fn physics_state(&self) -> Vec<f64> {
        self.data.state(MjtState::mjSTATE_INTEGRATION as u32).into_vec()
    }

    /// Restores a state read by [`Simulator::physics_state`] from a simulator of the same model, and
    /// recomputes the derived quantities (positions of bodies, sensors) from it.
    pub fn set_physics_state(&mut self, state: &[f64]) -> Result<(), ModelError> {
        let expected = self.data.model().state_size(MjtState::mjSTATE_INTEGRATION as u32);
        if state.len() != expected || !state.iter().all(|v| v.is_finite()) {
            return Err(invalid(
                "physics state".to_owned(),
                format!("{} numbers", state.len()),
                "must be the finite integration state of this model",
            ));
        }
        self.data
            .set_state(state, MjtState::mjSTATE_INTEGRATION as u32)
            .map_err(|e| invalid("physics state".to_owned(), e.to_string(), "MuJoCo rejected it"))?;
        self.data.forward();
        Ok(())
    }

    /// Sets the PD position targets of the five joints (radians, order q1..q5). MuJoCo clamps
    /// them to each actuator's control range.
    pub fn set_joint_targets(&mut self, targets_rad: &[f64; N_ACTUATED_JOINTS]) {
        let ctrl = self.data.ctrl_mut();
        for (i, &id) in self.layout.actuator_ids.iter().enumerate() {
            ctrl[id] = targets_rad[i];
        }
    }

    /// Advances `substeps` simulation steps (0.004 s each). Stops at the first MuJoCo warning or
    /// non-finite state and reports it; the caller should then reset.
    pub fn step(&mut self, substeps: usize) -> Result<(), SimFault> {
        for _ in 0..substeps {
            self.data.step();
            self.check_health()?;
        }
        Ok(())
    }

    fn check_health(&self) -> Result<(), SimFault> {
        let time_s = self.data.time();
        if let Some((kind, _)) = self.data.warning().iter().enumerate().find(|(_, w)| w.number > 0) {
            return Err(SimFault::MujocoWarning { warning: warning_name(kind), time_s });
        }
        if !self.data.qpos().iter().all(|x| x.is_finite()) {
            return Err(SimFault::NonFinite { field: "position", time_s });
        }
        if !self.data.qvel().iter().all(|x| x.is_finite()) {
            return Err(SimFault::NonFinite { field: "velocity", time_s });
        }
        Ok(())
    }

    // ----- reading the state -----

    pub fn time_s(&self) -> f64 {
        self.data.time()
    }

    pub fn timestep_s(&self) -> f64 {
        self.data.model_opt().timestep
    }

    /// Position of the main body's frame in the world (m).
    pub fn base_position_m(&self) -> Vec3 {
        let b = self.layout.base_qpos;
        Vec3::from_slice(&self.data.qpos()[b..b + 3])
    }

    /// Orientation of the main body (body to world).
    pub fn orientation(&self) -> Quat {
        let b = self.layout.base_qpos + 3;
        let q = &self.data.qpos()[b..b + 4];
        quat_from_wxyz([q[0], q[1], q[2], q[3]])
    }

    /// Linear velocity of the main body's frame in the world frame (m/s).
    pub fn linear_velocity_mps(&self) -> Vec3 {
        let b = self.layout.base_dof;
        Vec3::from_slice(&self.data.qvel()[b..b + 3])
    }

    /// Body-frame angular rates p, q, r (rad/s): about body x (roll), y (pitch, positive = nose down),
    /// z (yaw, positive = nose left).
    pub fn body_rates(&self) -> Vec3 {
        let b = self.layout.base_dof + 3;
        Vec3::from_slice(&self.data.qvel()[b..b + 3])
    }

    pub fn joint_positions(&self) -> [f64; N_ACTUATED_JOINTS] {
        let qpos = self.data.qpos();
        self.layout.joint_qpos.map(|adr| qpos[adr])
    }

    pub fn joint_velocities(&self) -> [f64; N_ACTUATED_JOINTS] {
        let qvel = self.data.qvel();
        self.layout.joint_dof.map(|adr| qvel[adr])
    }

    /// Lower and upper limit of each actuated joint (radians, order q1..q5).
    pub fn joint_ranges(&self) -> [[f64; 2]; N_ACTUATED_JOINTS] {
        let range = self.data.model().jnt_range();
        self.layout.joint_ids.map(|id| range[id])
    }

    /// The PD targets currently applied (radians).
    pub fn joint_targets(&self) -> [f64; N_ACTUATED_JOINTS] {
        let ctrl = self.data.ctrl();
        self.layout.actuator_ids.map(|id| ctrl[id])
    }

    /// Torque each actuator applies to its joint (N m), after the force limit.
    pub fn actuator_torques(&self) -> [f64; N_ACTUATED_JOINTS] {
        let force = self.data.actuator_force();
        self.layout.actuator_ids.map(|id| force[id])
    }

    /// Mechanical power the actuators deliver to the joints, sum of torque times joint velocity (W).
    /// Negative when the joints are driven back (the motors absorb energy).
    pub fn mechanical_power_w(&self) -> f64 {
        let (torque, velocity) = (self.actuator_torques(), self.joint_velocities());
        torque.iter().zip(velocity).map(|(t, v)| t * v).sum()
    }

    /// Pitot-tube airspeed: the body-x component of the velocity relative to the wind (m/s).
    pub fn pitot_airspeed_mps(&self) -> f64 {
        let air_relative = self.linear_velocity_mps() - self.wind();
        quat_rotate_inverse(self.orientation(), air_relative).x
    }

    // ----- editing parameters (per instance) -----

    /// The wind vector in the world frame (m/s).
    pub fn wind(&self) -> Vec3 {
        Vec3::from_array(self.data.model_opt().wind)
    }

    pub fn set_wind(&mut self, wind_mps: Vec3) -> Result<(), ModelError> {
        check_finite("wind", &wind_mps.to_array())?;
        self.data.model_opt_mut().wind = wind_mps.to_array();
        Ok(())
    }

    pub fn body_mass(&self, body: &str) -> Result<f64, ModelError> {
        Ok(self.data.model().body_mass()[self.body_id(body)?])
    }

    pub fn set_body_mass(&mut self, body: &str, mass_kg: f64) -> Result<(), ModelError> {
        let id = self.body_id(body)?;
        check_positive(&format!("mass of body '{body}'"), &[mass_kg])?;
        self.edit_model().body_mass_mut()[id] = mass_kg;
        self.constants_stale = true;
        Ok(())
    }

    /// Principal moments of inertia (kg m^2) in the body's inertial frame.
    pub fn body_inertia(&self, body: &str) -> Result<[f64; 3], ModelError> {
        Ok(self.data.model().body_inertia()[self.body_id(body)?])
    }

    pub fn set_body_inertia(&mut self, body: &str, inertia_kgm2: [f64; 3]) -> Result<(), ModelError> {
        let id = self.body_id(body)?;
        check_positive(&format!("inertia of body '{body}'"), &inertia_kgm2)?;
        self.edit_model().body_inertia_mut()[id] = inertia_kgm2;
        self.constants_stale = true;
        Ok(())
    }

    /// Centre of mass in the body's own frame (m).
    pub fn body_com(&self, body: &str) -> Result<Vec3, ModelError> {
        Ok(Vec3::from_array(self.data.model().body_ipos()[self.body_id(body)?]))
    }

    pub fn set_body_com(&mut self, body: &str, com_m: Vec3) -> Result<(), ModelError> {
        let id = self.body_id(body)?;
        check_finite(&format!("centre of mass of body '{body}'"), &com_m.to_array())?;
        self.edit_model().body_ipos_mut()[id] = com_m.to_array();
        self.constants_stale = true;
        Ok(())
    }

    /// Passive viscous damping of an actuated joint (N m s/rad).
    pub fn joint_damping(&self, joint: &str) -> Result<f64, ModelError> {
        Ok(self.data.model().dof_damping()[self.joint_dof(joint)?])
    }

    pub fn set_joint_damping(&mut self, joint: &str, damping: f64) -> Result<(), ModelError> {
        let dof = self.joint_dof(joint)?;
        check_not_negative(&format!("damping of joint '{joint}'"), &[damping])?;
        self.edit_model().dof_damping_mut()[dof] = damping;
        Ok(())
    }

    pub fn fluid_coefficients(&self, geom: &str) -> Result<FluidCoefficients, ModelError> {
        let fluid = self.data.model().geom_fluid()[self.lifting_geom_id(geom)?];
        Ok(FluidCoefficients::from_array(fluid[FLUID_COEFFICIENTS].try_into().expect("5 coefficients")))
    }

    pub fn set_fluid_coefficients(&mut self, geom: &str, coefficients: FluidCoefficients) -> Result<(), ModelError> {
        let id = self.lifting_geom_id(geom)?;
        let values = coefficients.to_array();
        check_not_negative(&format!("fluid coefficients of geom '{geom}'"), &values)?;
        self.edit_model().geom_fluid_mut()[id][FLUID_COEFFICIENTS].copy_from_slice(&values);
        Ok(())
    }

    /// The ellipsoid model's added (virtual) mass along the geom's axes (kg).
    pub fn added_mass(&self, geom: &str) -> Result<[f64; 3], ModelError> {
        let fluid = self.data.model().geom_fluid()[self.lifting_geom_id(geom)?];
        Ok(fluid[FLUID_ADDED_MASS].try_into().expect("3 values"))
    }

    pub fn set_added_mass(&mut self, geom: &str, added_mass_kg: [f64; 3]) -> Result<(), ModelError> {
        let id = self.lifting_geom_id(geom)?;
        check_not_negative(&format!("added mass of geom '{geom}'"), &added_mass_kg)?;
        self.edit_model().geom_fluid_mut()[id][FLUID_ADDED_MASS].copy_from_slice(&added_mass_kg);
        Ok(())
    }

    /// The ellipsoid model's added (virtual) moment of inertia about the geom's axes (kg m^2).
    pub fn added_inertia(&self, geom: &str) -> Result<[f64; 3], ModelError> {
        let fluid = self.data.model().geom_fluid()[self.lifting_geom_id(geom)?];
        Ok(fluid[FLUID_ADDED_INERTIA].try_into().expect("3 values"))
    }

    pub fn set_added_inertia(&mut self, geom: &str, added_inertia_kgm2: [f64; 3]) -> Result<(), ModelError> {
        let id = self.lifting_geom_id(geom)?;
        check_not_negative(&format!("added inertia of geom '{geom}'"), &added_inertia_kgm2)?;
        self.edit_model().geom_fluid_mut()[id][FLUID_ADDED_INERTIA].copy_from_slice(&added_inertia_kgm2);
        Ok(())
    }

    /// Puts every editable parameter back to the loaded model's value.
    pub fn restore_nominal_parameters(&mut self) {
        let nominal_robot = self.nominal.clone();
        let nominal = nominal_robot.mujoco();
        let (mass, inertia, com) = (nominal.body_mass(), nominal.body_inertia(), nominal.body_ipos());
        let (damping, fluid, wind) = (nominal.dof_damping(), nominal.geom_fluid(), nominal.opt().wind);
        let model = self.edit_model();
        // Only mass, inertia and centre-of-mass changes need MuJoCo's constants recomputed at reset.
        let inertial_changed = model.body_mass() != mass || model.body_inertia() != inertia || model.body_ipos() != com;
        if inertial_changed {
            model.body_mass_mut().copy_from_slice(mass);
            model.body_inertia_mut().copy_from_slice(inertia);
            model.body_ipos_mut().copy_from_slice(com);
        }
        model.dof_damping_mut().copy_from_slice(damping);
        model.geom_fluid_mut().copy_from_slice(fluid);
        model.opt_mut().wind = wind;
        self.constants_stale |= inertial_changed;
    }

    /// The model this instance simulates, with its edits (read-only).
    pub fn mujoco_model(&self) -> &MjModel {
        self.data.model()
    }

    fn edit_model(&mut self) -> &mut MjModel {
        // SAFETY: callers only change values (masses, inertias, centres of mass, damping, fluid
        // parameters, wind), never sizes, addresses or indices, so the data stays consistent with
        // the model; derived constants are recomputed by `mj_setConst` at the next reset.
        unsafe { self.data.model_mut() }
    }

    fn body_id(&self, body: &str) -> Result<usize, ModelError> {
        if !BODY_NAMES.contains(&body) {
            return Err(unknown("body", body, &BODY_NAMES));
        }
        self.data.model().name_to_id(MjtObjBase::mjOBJ_BODY, body).ok_or_else(|| unknown("body", body, &BODY_NAMES))
    }

    fn joint_dof(&self, joint: &str) -> Result<usize, ModelError> {
        ActuatedJoint::ALL
            .iter()
            .position(|j| j.name() == joint)
            .map(|i| self.layout.joint_dof[i])
            .ok_or_else(|| unknown("joint", joint, &ActuatedJoint::ALL.map(ActuatedJoint::name)))
    }

    fn lifting_geom_id(&self, geom: &str) -> Result<usize, ModelError> {
        let err = || unknown("lifting-surface geom", geom, &LIFTING_SURFACE_GEOMS);
        if !LIFTING_SURFACE_GEOMS.contains(&geom) {
            return Err(err());
        }
        self.data.model().name_to_id(MjtObjBase::mjOBJ_GEOM, geom).ok_or_else(err)
    }
}

fn warning_name(kind: usize) -> &'static str {
    // Order of MuJoCo 3.17's mjtWarning.
    const NAMES: [&str; 7] =
        ["inertia", "contact buffer full", "constraint buffer full", "bad qpos", "bad qvel", "bad qacc", "bad ctrl"];
    NAMES.get(kind).copied().unwrap_or("unknown")
}

fn unknown(kind: &'static str, name: &str, known: &[&str]) -> ModelError {
    ModelError::UnknownName { kind, name: name.to_owned(), known: known.join(", ") }
}

fn invalid(what: String, value: impl std::fmt::Debug, why: &'static str) -> ModelError {
    ModelError::InvalidValue { what, value: format!("{value:?}"), why }
}

fn check_finite(what: &str, values: &[f64]) -> Result<(), ModelError> {
    if values.iter().all(|v| v.is_finite()) { Ok(()) } else { Err(invalid(what.to_owned(), values, "must be finite")) }
}

fn check_positive(what: &str, values: &[f64]) -> Result<(), ModelError> {
    if values.iter().all(|v| v.is_finite() && *v > 0.0) {
        Ok(())
    } else {
        Err(invalid(what.to_owned(), values, "must be finite and positive"))
    }
}

fn check_not_negative(what: &str, values: &[f64]) -> Result<(), ModelError> {
    if values.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(invalid(what.to_owned(), values, "must be finite and not negative"))
    }
}
