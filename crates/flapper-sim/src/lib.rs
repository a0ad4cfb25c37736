//! The simulator layer: the first stage of the flow
//! `robot model (MJCF) -> simulator (MuJoCo) -> task -> vectorized environments -> learner -> evaluation`.
//!
//! It loads the robot's MJCF model ([`RobotModel`]), gives each environment its own MuJoCo instance
//! ([`Simulator`]) that can be reset, driven with the five joint targets, stepped, read and edited
//! (masses, inertias, centres of mass, damping, fluid coefficients, wind). It knows nothing of
//! trajectories, rewards or learning. A MuJoCo warning or a non-finite state comes back as a
//! [`SimFault`], never as a panic or a silent NaN.

pub mod benchmark;
mod error;
mod geometry;
mod mjcf_numbers;
mod model;
mod robot;
mod simulator;

pub use error::{ModelError, SimFault};
pub use geometry::{Quat, Vec3, quat_from_euler, quat_from_wxyz, quat_rotate_inverse, quat_to_euler, quat_to_wxyz};
pub use model::RobotModel;
pub use robot::{
    ActuatedJoint, BASE_JOINT, BODY_NAMES, CRUISE_SPEED_MPS, LIFTING_SURFACE_GEOMS, N_ACTUATED_JOINTS, ROBOT_MJCF,
    default_model_path,
};
pub use simulator::{FluidCoefficients, InitialState, Simulator};
