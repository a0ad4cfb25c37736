//! Loading the robot's MJCF into MuJoCo and finding its parts by name. A [`RobotModel`] is the
//! shared, read-only template; each environment gets its own `Simulator` from it (`instantiate`, defined
//! beside the simulator, which is built from the model).

use std::path::Path;
use std::sync::Arc;

use mujoco_rs::prelude::*;

use crate::error::ModelError;
use crate::robot::{ActuatedJoint, BASE_JOINT, BODY_NAMES, LIFTING_SURFACE_GEOMS, N_ACTUATED_JOINTS, ROBOT_MJCF};

/// Indices into MuJoCo's arrays, resolved once from names.
#[derive(Debug, Clone)]
pub(crate) struct Layout {
    pub base_qpos: usize,
    pub base_dof: usize,
    pub joint_ids: [usize; N_ACTUATED_JOINTS],
    pub joint_qpos: [usize; N_ACTUATED_JOINTS],
    pub joint_dof: [usize; N_ACTUATED_JOINTS],
    pub actuator_ids: [usize; N_ACTUATED_JOINTS],
}

/// The robot model loaded into MuJoCo, validated and with its parts resolved.
#[derive(Debug, Clone)]
pub struct RobotModel {
    origin: String,
    /// The MJCF text it was compiled from (the renderer adds its scenery to a copy).
    mjcf: Arc<str>,
    nominal: Arc<MjModel>,
    layout: Arc<Layout>,
}

/// Size of the model as built, for checking against the paper.
#[derive(Debug, Clone, Copy)]
pub struct Dimensions {
    pub total_mass_kg: f64,
    /// Tip to tip with the wings flat.
    pub wingspan_m: f64,
    /// Wing area divided by the wing's own span (the "standard mean chord" of one wing).
    pub mean_chord_m: f64,
    pub degrees_of_freedom: usize,
    pub actuators: usize,
}

impl RobotModel {
    /// The robot shipped with flapper (`models/flapper.xml`, compiled in).
    pub fn flapper() -> Result<Self, ModelError> {
        Self::from_mjcf(ROBOT_MJCF, "models/flapper.xml")
    }

    /// Loads an MJCF file.
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        let origin = path.display().to_string();
        // Read it ourselves first: MuJoCo's message for a missing file is less clear than the OS's.
        let mjcf =
            std::fs::read_to_string(path).map_err(|source| ModelError::Read { path: path.to_owned(), source })?;
        refuse_non_finite(&mjcf, &origin)?;
        let model =
            MjModel::from_xml(path).map_err(|e| ModelError::Load { origin: origin.clone(), message: e.to_string() })?;
        Self::from_mujoco(model, origin, mjcf.into())
    }

    /// Loads MJCF text; `origin` names it in error messages.
    pub fn from_mjcf(mjcf: &str, origin: &str) -> Result<Self, ModelError> {
        refuse_non_finite(mjcf, origin)?;
        let model = MjModel::from_xml_string(mjcf)
            .map_err(|e| ModelError::Load { origin: origin.to_owned(), message: e.to_string() })?;
        Self::from_mujoco(model, origin.to_owned(), mjcf.into())
    }

    fn from_mujoco(model: MjModel, origin: String, mjcf: Arc<str>) -> Result<Self, ModelError> {
        let not_robot = |problem: String| ModelError::NotTheRobot { origin: origin.clone(), problem };
        let base = model
            .name_to_id(MjtObjBase::mjOBJ_JOINT, BASE_JOINT)
            .ok_or_else(|| not_robot(format!("no free joint named '{BASE_JOINT}'")))?;
        if model.jnt_type()[base] != MjtJoint::mjJNT_FREE {
            return Err(not_robot(format!("joint '{BASE_JOINT}' is not a free joint")));
        }
        for body in BODY_NAMES {
            model
                .name_to_id(MjtObjBase::mjOBJ_BODY, body)
                .ok_or_else(|| not_robot(format!("no body named '{body}'")))?;
        }
        let mut joint_ids = [0; N_ACTUATED_JOINTS];
        let mut joint_qpos = [0; N_ACTUATED_JOINTS];
        let mut joint_dof = [0; N_ACTUATED_JOINTS];
        let mut actuator_ids = [0; N_ACTUATED_JOINTS];
        for joint in ActuatedJoint::ALL {
            let i = joint.index();
            let id = model
                .name_to_id(MjtObjBase::mjOBJ_JOINT, joint.name())
                .ok_or_else(|| not_robot(format!("no joint named '{}'", joint.name())))?;
            if model.jnt_type()[id] != MjtJoint::mjJNT_HINGE {
                return Err(not_robot(format!("joint '{}' is not a hinge", joint.name())));
            }
            let actuator = model
                .name_to_id(MjtObjBase::mjOBJ_ACTUATOR, joint.name())
                .ok_or_else(|| not_robot(format!("no actuator named '{}'", joint.name())))?;
            if model.actuator_trnid()[actuator][0] as usize != id {
                return Err(not_robot(format!("actuator '{}' does not drive joint '{}'", joint.name(), joint.name())));
            }
            joint_ids[i] = id;
            joint_qpos[i] = model.jnt_qposadr()[id] as usize;
            joint_dof[i] = model.jnt_dofadr()[id] as usize;
            actuator_ids[i] = actuator;
        }
        check_physical(&model, &origin)?;
        let layout = Layout {
            base_qpos: model.jnt_qposadr()[base] as usize,
            base_dof: model.jnt_dofadr()[base] as usize,
            joint_ids,
            joint_qpos,
            joint_dof,
            actuator_ids,
        };
        Ok(Self { origin, mjcf, nominal: Arc::new(model), layout: Arc::new(layout) })
    }

    /// Where the model came from (a path, or a name given with the text).
    pub fn origin(&self) -> &str {
        &self.origin
    }

    /// The MJCF text the model was compiled from.
    pub fn mjcf(&self) -> &str {
        &self.mjcf
    }

    /// The underlying MuJoCo model (read-only; every simulator edits its own copy).
    pub fn mujoco(&self) -> &MjModel {
        &self.nominal
    }

    pub(crate) fn layout(&self) -> &Arc<Layout> {
        &self.layout
    }

    /// Simulation time step in seconds (0.004 s: 250 Hz).
    pub fn timestep_s(&self) -> f64 {
        self.nominal.opt().timestep
    }

    /// Mass, wingspan, mean chord, DoF and actuator count of the model as built.
    pub fn dimensions(&self) -> Dimensions {
        let model = &*self.nominal;
        let mut data = MjData::new(model);
        data.forward();
        let geom = |name: &str| model.name_to_id(MjtObjBase::mjOBJ_GEOM, name);
        let (left, right) = (geom(LIFTING_SURFACE_GEOMS[0]), geom(LIFTING_SURFACE_GEOMS[1]));
        let (wingspan_m, mean_chord_m) = match (left, right) {
            (Some(l), Some(r)) => {
                let xpos = data.geom_xpos();
                let size = model.geom_size();
                // Wings flat: each ellipsoid's span semi-axis lies along world y.
                let span = (xpos[l][1] + size[l][1]) - (xpos[r][1] - size[r][1]);
                // Elliptic planform: area pi * a * b over span 2 b.
                let chord = std::f64::consts::PI * size[l][0] / 2.0;
                (span, chord)
            }
            _ => (f64::NAN, f64::NAN),
        };
        Dimensions {
            total_mass_kg: model.totalmass(),
            wingspan_m,
            mean_chord_m,
            degrees_of_freedom: model.ffi().nv as usize,
            actuators: model.ffi().nu as usize,
        }
    }
}

/// Numbers no simulation of this robot could run on: a timestep outside [1 us, 10 ms] (the control loop
/// needs several substeps per 20 ms), non-finite or non-positive masses and inertias, non-finite or
/// negative damping, fluid coefficients, density and viscosity, joint ranges that are not finite or do
/// not contain zero.
/// A NaN or infinity in any numeric attribute, refused before MuJoCo reads the text.
fn refuse_non_finite(mjcf: &str, origin: &str) -> Result<(), ModelError> {
    match crate::mjcf_numbers::first_non_finite(mjcf) {
        Some(found) => Err(ModelError::Unphysical {
            origin: origin.to_owned(),
            problem: format!("line {}: {}=\"{}\" is not a finite number", found.line, found.attribute, found.value),
        }),
        None => Ok(()),
    }
}

fn check_physical(model: &MjModel, origin: &str) -> Result<(), ModelError> {
    let fail = |problem: String| Err(ModelError::Unphysical { origin: origin.to_owned(), problem });
    let timestep = model.opt().timestep;
    if !(timestep.is_finite() && (1e-6..=0.01).contains(&timestep)) {
        return fail(format!("timestep {timestep:e} s is outside [1e-6, 0.01] s"));
    }
    for (what, value) in [("density", model.opt().density), ("viscosity", model.opt().viscosity)] {
        if !(value.is_finite() && (0.0..=1e4).contains(&value)) {
            return fail(format!("{what} {value:e} is outside [0, 1e4]"));
        }
    }
    for body in BODY_NAMES {
        let id = model.name_to_id(MjtObjBase::mjOBJ_BODY, body).expect("checked above");
        let mass = model.body_mass()[id];
        if !(mass.is_finite() && mass > 0.0 && mass <= 100.0) {
            return fail(format!("body '{body}' has mass {mass:e} kg (must be in (0, 100] kg)"));
        }
        if let Some(i) = model.body_inertia()[id].iter().find(|i| !(i.is_finite() && **i >= 0.0 && **i <= 100.0)) {
            return fail(format!("body '{body}' has inertia {i:e} kg m^2 (must be in [0, 100])"));
        }
    }
    if let Some(d) = model.dof_damping().iter().find(|d| !(d.is_finite() && **d >= 0.0)) {
        return fail(format!("a joint has damping {d:e} (must be finite and non-negative)"));
    }
    for geom in LIFTING_SURFACE_GEOMS {
        if let Some(id) = model.name_to_id(MjtObjBase::mjOBJ_GEOM, geom)
            && let Some(v) = model.geom_fluid()[id].iter().find(|v| !(v.is_finite() && v.abs() <= 1e6))
        {
            return fail(format!("geom '{geom}' has fluid parameter {v:e} (must be finite)"));
        }
    }
    for joint in ActuatedJoint::ALL {
        let id = model.name_to_id(MjtObjBase::mjOBJ_JOINT, joint.name()).expect("checked above");
        let [low, high] = model.jnt_range()[id];
        // Actions map to +-min(high, -low) about zero, so the range must contain zero on both sides.
        if !(low.is_finite() && high.is_finite() && low < 0.0 && high > 0.0) {
            return fail(format!(
                "joint '{}' has range [{low:e}, {high:e}] (must be finite and contain 0 inside it)",
                joint.name()
            ));
        }
    }
    Ok(())
}
