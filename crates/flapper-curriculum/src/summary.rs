//! `summary.json`: the seed, the command, and per stage its iterations, environment steps, wall time,
//! the checkpoint it handed over and that checkpoint's validation score; for a run stopped by a missed
//! gate, that stage's spending and best score (`stopped`); for a run ended by an optional stage that missed its
//! gate, the same for that stage (`optional_stage_missed`), the run ending with the stage before it; the
//! totals, the stopped or missed stage included.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::config::CurriculumConfig;
use crate::error::CurriculumError;
use crate::selection::{StageOutcome, StoppedStage};

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub seed: u64,
    pub command: String,
    pub stages: Vec<StageOutcome>,
    /// The stage whose missed gate stopped the run; absent in a run that did not stop.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped: Option<StoppedStage>,
    /// The optional stage whose gate was missed, or which the budget left too little to start
    /// (`iterations` 0; [`crate::config::StageConfig::optional`]): the run ended with the controller of the
    /// last of `stages`, not this one's. Absent where none was missed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub optional_stage_missed: Option<StoppedStage>,
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
            stopped: None,
            optional_stage_missed: None,
            total_env_steps: stages.iter().map(|s| s.env_steps).sum(),
            total_wall_time_s: stages.iter().map(|s| s.wall_time_s).sum(),
        }
    }

    /// The summary of a run that `stopped` stage's missed gate ended: its steps and time join the totals.
    pub fn stopped_at(mut self, stopped: StoppedStage) -> Self {
        self.count(&stopped);
        self.stopped = Some(stopped);
        self
    }

    /// The summary of a run whose optional stage `missed` its gate: the run ends with the stages
    /// before it, and the missed stage's steps and time join the totals.
    pub fn optional_missed(mut self, missed: StoppedStage) -> Self {
        self.count(&missed);
        self.optional_stage_missed = Some(missed);
        self
    }

    /// Adds what a stage that handed nothing over spent to the totals.
    fn count(&mut self, stage: &StoppedStage) {
        self.total_env_steps += stage.env_steps;
        self.total_wall_time_s += stage.wall_time_s;
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
