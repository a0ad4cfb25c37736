//! What can stop a training run (`TrainError`): a checkpoint or an environment that fails, a run folder
//! that holds another run, is locked by another trainer or holds nothing to resume, a damaged
//! `training.csv`, a file that cannot be written. Shared by the runner and the files it keeps
//! (`run_folder`, `training_log`), so that none of them has to import another for its errors.

use std::path::PathBuf;

use crate::checkpoint::CheckpointError;
use crate::vec_env::EnvError;

#[derive(Debug, thiserror::Error)]
pub enum TrainError {
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error("environment: {0}")]
    Env(EnvError),
    #[error("'{0}' already holds a training run; resume it, or train into another folder")]
    RunExists(PathBuf),
    #[error(
        "'{dir}' already holds {file}, which a new run would overwrite; give --out a new or empty folder (or move the file)"
    )]
    WouldOverwrite { dir: PathBuf, file: &'static str },
    #[error(
        "cannot resume: '{path}' {problem}; the checkpoints are intact: restore the file, or move it away to resume with a new log from the checkpoint on"
    )]
    DamagedLog { path: PathBuf, problem: String },
    #[error(
        "another training process is using '{0}' (it holds the folder's lock file .lock); wait for it to end or train into another folder"
    )]
    Busy(PathBuf),
    #[error("'{0}' has no checkpoint to resume from (checkpoints/iter_*.safetensors)")]
    NothingToResume(PathBuf),
    #[error("cannot write '{path}': {message}")]
    Output { path: PathBuf, message: String },
    #[error(
        "'{0}' holds no environment state (written by an older flapper, whose runs restarted their environments at every checkpoint); start a new run from its policy instead"
    )]
    NoEnvironmentState(PathBuf),
    #[error(
        "the run reached {iterations} iterations already (checkpoint at iteration {done}); raise the iteration count to train further"
    )]
    AlreadyDone { iterations: usize, done: usize },
}
