//! The task layer (paper III-A to III-F): between the simulator and whatever decides the joint targets
//! (a learned policy or a scripted baseline).
//!
//! - `config`: every number of the task, the paper's defaults, TOML overrides, curriculum stages;
//! - `control_loop`, `action_filter`, `action`: 50 Hz actions in [-1, 1] scaled to the joint limits,
//!   smoothed by the 7 Hz filter at the 250 Hz simulation rate, tracked by the PD servos;
//! - `reference`: procedural, named and CSV reference paths;
//! - `observation`, `reward`, `termination`, `randomization`: what the policy sees, earns, ends on and
//!   is trained against;
//! - `flap_rhythm`: the flap frequency read online, for the price on a fast stroke;
//! - `env`, `vec_env`: one environment, and N of them stepped in parallel.

pub mod action;
mod action_filter;
pub mod benchmark;
pub mod config;
mod control_loop;
pub mod env;
pub mod flap_rhythm;
pub mod observation;
pub mod randomization;
pub mod reference;
pub mod reward;
pub mod termination;
pub mod vec_env;

pub use action_filter::LowPassFilter;
pub use config::{ControlConfig, TaskConfig};
pub use control_loop::{ControlLoop, JointWork};
pub use env::{EpisodeInfo, FlightEnv, ReferenceSource};
pub use vec_env::FlightVecEnv;
