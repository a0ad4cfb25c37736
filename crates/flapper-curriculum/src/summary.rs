//! `summary.json`: the seed, the command, and per stage its iterations, environment steps, wall time,
//! the checkpoint it handed over and that checkpoint's validation score; the totals.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::config::CurriculumConfig;
use crate::run::CurriculumError;
use crate::selection::StageOutcome;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub seed: u64,
    pub command: String,
    pub stages: Vec<StageOutcome>,
    pub total_env_steps: u64,
    /// Training and validation of every stage (not the time a run stood interrupted).
    pub total_wall_time_s: f64,
}

impl Summary {
    pub fn new(config: &CurriculumConfig, command: &str, stages: &[StageOutcome]) -> Self {
        Self {
            seed: config.seed,
            command: command.to_owned(),
            stages: stages.to_vec(),
            total_env_steps: stages.iter().map(|s| s.env_steps).sum(),
            total_wall_time_s: stages.iter().map(|s| s.wall_time_s).sum(),
        }
    }

    pub fn write(&self, path: &Path) -> Result<(), CurriculumError> {
        flapper_files::write_json(path, self)
            .map_err(|e| CurriculumError::File { path: path.to_owned(), message: e.to_string() })
    }

    /// A curriculum folder's `summary.json` (`dir/summary.json`).
    pub fn read(dir: &Path) -> Result<Self, CurriculumError> {
        let path = dir.join("summary.json");
        flapper_files::read_json(&path).map_err(|message| CurriculumError::File { path: path.clone(), message })
    }
}
