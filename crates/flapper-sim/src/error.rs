//! Errors of the simulator layer: what went wrong loading or editing a model, and what a running
//! simulation reports when MuJoCo warns or the state stops being finite.

use std::path::PathBuf;

/// Loading the robot model or editing one of its parameters failed.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    #[error("cannot read model file '{path}'")]
    Read { path: PathBuf, source: std::io::Error },
    #[error("MuJoCo rejected model '{origin}': {message}")]
    Load { origin: String, message: String },
    #[error("model '{origin}' is not the flapping-wing robot: {problem}")]
    NotTheRobot { origin: String, problem: String },
    #[error("model '{origin}': {problem}")]
    Unphysical { origin: String, problem: String },
    #[error("unknown {kind} '{name}' (known: {known})")]
    UnknownName { kind: &'static str, name: String, known: String },
    #[error("invalid value for {what}: {value} ({why})")]
    InvalidValue { what: String, value: String, why: &'static str },
}

/// A running simulation went wrong. The state is no longer trustworthy: the caller resets.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimFault {
    #[error("MuJoCo warning '{warning}' at t = {time_s:.3} s")]
    MujocoWarning { warning: &'static str, time_s: f64 },
    #[error("non-finite {field} at t = {time_s:.3} s")]
    NonFinite { field: &'static str, time_s: f64 },
}
