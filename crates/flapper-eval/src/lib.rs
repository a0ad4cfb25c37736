//! Evaluation: the last stages of the flow, where a controller flies the robot and the flight is
//! measured, saved and plotted. Holds the baseline controllers (a glide and the scripted flapping
//! gait) that learned policies are compared against.

mod controller;
mod flight;
mod flight_log;
mod plots;
pub mod policy_file;
mod scripted;
pub mod spectrum;
pub mod tracking;
pub mod tracking_report;

pub use controller::{Controller, FlightState, GlideController};
pub use flight::{FlightSpec, fly, fly_simulator};
pub use flight_log::{FlightLog, FlightRow, FlightSummary};
pub use plots::{write_flight_plots, write_path_views};
pub use policy_file::{FlightPolicyFile, PolicyFileError, load_flight_policy, load_flight_policy_file};
pub use scripted::{ScriptedGait, ScriptedGaitConfig};

/// Writing results failed.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write '{path}': {message}")]
    Write { path: std::path::PathBuf, message: String },
}
