//! The training method in one command (`flapper curriculum`): the paper's four stages trained in turn
//! from one TOML (`config`; a file may build on another, `overlay`), every few iterations each
//! checkpoint flown on a validation set and scored (`validation`), the best one handed to the next stage
//! (`selection`), gates that stop a run which does not learn (`run`; what can stop it: `error`), and the
//! record of it all (`summary`, `figure`). Downstream of training and evaluation, which it drives;
//! nothing upstream knows of it.

pub mod config;
pub mod error;
pub mod figure;
pub mod flight_modes;
pub mod identification;
pub mod machine;
pub mod overlay;
pub mod run;
pub mod selection;
pub mod summary;
pub mod validation;

pub use config::CurriculumConfig;
pub use error::CurriculumError;
pub use run::{CurriculumRequest, Progress, run_curriculum};
