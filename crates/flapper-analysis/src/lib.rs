//! Analysis of a trained flight controller in closed loop (paper IV-A), downstream of evaluation:
//!
//! - [`linear_system`]: continuous-time transfer functions: roots by companion-matrix eigenvalues,
//!   poles, zeros, DC gain, the stability and minimum-phase verdicts, simulation;
//! - [`fit`]: third-order transfer functions fitted to input-output records (state-variable-filter
//!   least squares), with one denominator shared by the axes or one per axis;
//! - [`sysid`]: the identification experiment on a policy (perturbed cruise references flown from an
//!   exact start), its report, files and plots;
//! - [`phase`]: phase portraits of the wings in cruise, climb and a left turn, and the paper's claims
//!   about them checked;
//! - [`modes`]: flight modes along the longitudinal reference (does the policy glide?);
//! - [`robustness`]: success rates under randomized fluid coefficients, constant winds and all of
//!   Table III, and the level-flight airspeed envelope (paper Fig. 8-9);
//! - [`frontier`]: energy against tracking per controller (the efficient-bird trade-off), with the
//!   glide fraction, the cruise flap frequency and slow level flight;
//! - [`power_curve`]: what straight and level flight costs at each airspeed: the scripted gait's
//!   family, the cheapest gait per airspeed, and policies on level paths beside it.

pub mod fit;
pub mod frontier;
pub mod linear_system;
pub mod modes;
pub mod phase;
pub mod power_curve;
pub mod robustness;
pub mod sysid;

/// `task` with its randomized start removed (no position, speed or attitude offset): the one flight
/// from the reference's exact start that `flapper modes`, `phase` and `sysid` analyse.
pub(crate) fn exact_start(task: &flapper_task::TaskConfig) -> flapper_task::TaskConfig {
    let mut exact = task.clone();
    exact.initial_state.position_offset_m = [0.0; 3];
    exact.initial_state.speed_offset_mps = 0.0;
    exact.initial_state.attitude_offset_deg = 0.0;
    exact
}

/// What can go wrong in an analysis: a flight the policy cannot make, a fit, an output file.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    #[error(transparent)]
    Model(#[from] flapper_sim::ModelError),
    #[error(
        "the policy did not fly identification record {record} (seed {seed}): it ended '{end}' at {time_s:.1} s of {length_s:.0} s; it cannot cruise at 3.8 m/s with its target perturbed by {amplitude_m} m"
    )]
    RecordFailed { record: usize, seed: u64, end: &'static str, time_s: f64, length_s: f64, amplitude_m: f64 },
    #[error("the policy cannot fly the {what}: it ended '{end}' at {time_s:.1} s")]
    FlightFailed { what: String, end: &'static str, time_s: f64 },
    #[error(
        "the identification is set up for the paper's 50 Hz control rate (0.02 s); this model and task step every {period_s} s"
    )]
    ControlRate { period_s: f64 },
    #[error("the least-squares fit failed (too little data, or a constant input)")]
    FitFailed,
    #[error("cannot write '{path}': {message}")]
    Write { path: std::path::PathBuf, message: String },
    #[error("cannot read '{path}': {message}")]
    Read { path: std::path::PathBuf, message: String },
    /// A row of a trade-off file (`frontier.csv`, or points measured elsewhere) that does not parse.
    #[error("'{path}' line {line}: {message}")]
    FrontierFile { path: std::path::PathBuf, line: u64, message: String },
    #[error(transparent)]
    Reference(#[from] flapper_task::reference::ReferenceError),
    #[error("'{0}' is not a named reference (flapper reference --list)")]
    UnknownReference(String),
}
