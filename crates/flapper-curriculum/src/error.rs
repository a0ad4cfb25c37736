//! What can stop a curriculum run (`CurriculumError`): a folder that is not a curriculum or holds one
//! with other settings, one another process is running, a missed gate, a budget spent before a stage,
//! and the failures of training, validation, selection, checkpoints and files beneath them. Shared by
//! the run and the files it keeps (`summary`).

use std::path::PathBuf;

use flapper_ppo::checkpoint::CheckpointError;
use flapper_train::run::RunError;

use crate::selection::{SelectionError, StoppedStage};
use crate::validation::ValidationError;

#[derive(Debug, thiserror::Error)]
pub enum CurriculumError {
    #[error("'{0}' holds files that are not a curriculum run (no curriculum.toml); choose a new or empty folder")]
    NotACurriculum(PathBuf),
    #[error(
        "'{dir}' holds a curriculum started with other settings ({what} differs from its curriculum.toml); continue it with the same settings or choose another folder"
    )]
    OtherSettings { dir: PathBuf, what: &'static str },
    #[error(
        "'{dir}' has started stage {stage} ('{name}') with other settings than the curriculum given; a folder continues only with the stages it has started unchanged (later ones may change): continue it with its curriculum.toml or choose another folder"
    )]
    StartedStageChanged { dir: PathBuf, stage: usize, name: String },
    #[error("another process is running the curriculum in '{0}' (its .lock is held)")]
    Busy(PathBuf),
    #[error(
        "stage {} ('{}') missed its gate ({}) within {} iterations; its best checkpoint, {best}.{} Its runs are in '{dir}'; what to try next (more budget, another seed, or for a robot of your own a controller fine-tuned from one that flies these references): docs/training.md, \"Training your own robot\"",
        .stopped.stage, .stopped.name, .stopped.gate, .stopped.iterations,
        .stopped.stopped_because.as_ref().map_or(String::new(), |why| format!(" No more iterations: {why}."))
    )]
    GateMissed {
        /// The stage, its gate, what it spent and the best score it reached (also `stopped` in `summary.json`).
        stopped: Box<StoppedStage>,
        /// The best checkpoint's iteration and score, and the identification of those identified.
        best: String,
        dir: PathBuf,
    },
    #[error(
        "stage {stage} ('{name}') cannot start: the curriculum's max_env_steps ({budget}) leaves {left} environment steps after the stages before it, {iterations} iterations, and the stage needs at least {needed} (one validation interval, or its gate's min_iterations); raise max_env_steps or lower an earlier stage's max_iterations"
    )]
    BudgetSpent { stage: usize, name: String, budget: u64, left: u64, iterations: usize, needed: usize },
    #[error(transparent)]
    Run(#[from] RunError),
    #[error(transparent)]
    Train(#[from] flapper_ppo::TrainError),
    #[error(transparent)]
    Validation(#[from] ValidationError),
    #[error(transparent)]
    Selection(#[from] SelectionError),
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error("'{path}': {message}")]
    File { path: PathBuf, message: String },
}
