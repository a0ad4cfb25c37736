//! Analysis of a trained flight controller in closed loop (paper IV-A), downstream of evaluation:
//!
//! - [`linear_system`]: continuous-time transfer functions: roots by companion-matrix eigenvalues,
//!   poles, zeros, DC gain, the stability and minimum-phase verdicts, simulation;
//! - [`fit`]: third-order transfer functions fitted to input-output records (state-variable-filter
//!   least squares), with one denominator shared by the axes or one per axis;
//! - [`sysid`]: the identification experiment on a policy (perturbed cruise references flown from an
//!   exact start), its report, files and plots.

pub mod fit;
pub mod linear_system;
pub mod sysid;
