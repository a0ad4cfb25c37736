//! A training run's folder, apart from the learner that fills it: which files it holds, the lock that
//! keeps a second trainer out, what a new run refuses to overwrite, and where the checkpoints are.
//!
//! Layout: `config.toml` (the full config), `training.csv` (one row per iteration),
//! `checkpoints/iter_NNNNNN.safetensors` (+ `.json`), and at the end `policy.safetensors` (+ `.json`);
//! `learning_curves.svg` from the training crate's checkpoint hook; `.lock` while a trainer runs.

use std::path::{Path, PathBuf};

use crate::checkpoint;
use crate::train_error::TrainError;

/// The files a run writes in its folder besides the checkpoints: a new run refuses a
/// folder that holds any of them, so it never overwrites a user's own file.
pub const RUN_FILES: [&str; 5] =
    ["config.toml", "policy.safetensors", "policy.safetensors.json", "learning_curves.svg", "training.csv"];

/// A run folder this process owns: its lock is held until the value is dropped (or the process ends,
/// however it ends).
#[derive(Debug)]
pub struct RunFolder {
    dir: PathBuf,
    _lock: std::fs::File,
}

impl RunFolder {
    /// Refuses `dir` for a new run when it holds a run or a file a run would write. Cheap and
    /// side-effect free: called before anything else is loaded, and again under the lock by `create`.
    pub fn check_new(dir: &Path) -> Result<(), TrainError> {
        if latest_checkpoint(dir).is_some() || dir.join("training.csv").exists() {
            return Err(TrainError::RunExists(dir.to_owned()));
        }
        if let Some(file) = RUN_FILES.into_iter().find(|file| dir.join(file).exists()) {
            return Err(TrainError::WouldOverwrite { dir: dir.to_owned(), file });
        }
        Ok(())
    }

    /// Makes `dir` a new run's folder: created with its checkpoint folder, locked, `config.toml`
    /// written.
    pub fn create(dir: &Path, config_toml: &str) -> Result<Self, TrainError> {
        Self::check_new(dir)?;
        std::fs::create_dir_all(checkpoint_dir(dir))
            .map_err(|e| TrainError::Output { path: dir.to_owned(), message: e.to_string() })?;
        let folder = Self { dir: dir.to_owned(), _lock: lock(dir)? };
        // Again under the lock: another trainer may have started here since the check above (which
        // keeps a refused start from creating the folder and its lock file).
        Self::check_new(dir)?;
        checkpoint::write_atomically(&dir.join("config.toml"), config_toml.as_bytes())?;
        Ok(folder)
    }

    /// Takes over an existing run to continue it: the folder, locked, and its newest checkpoint.
    /// A folder another trainer still holds is busy, also before its first checkpoint.
    pub fn open(dir: &Path) -> Result<(Self, PathBuf), TrainError> {
        // The lock first where the folder has one (a run's folder), so that a run still before its first
        // checkpoint is reported as busy, not as empty; no lock file is made in a folder that is no run.
        let early_lock = dir.join(".lock").is_file().then(|| lock(dir)).transpose()?;
        let newest = latest_checkpoint(dir).ok_or_else(|| TrainError::NothingToResume(dir.to_owned()))?;
        let lock = early_lock.map_or_else(|| lock(dir), Ok)?;
        Ok((Self { dir: dir.to_owned(), _lock: lock }, newest))
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    pub fn training_csv(&self) -> PathBuf {
        self.dir.join("training.csv")
    }

    /// The final policy, written when the run ends.
    pub fn policy(&self) -> PathBuf {
        self.dir.join("policy.safetensors")
    }

    /// Where the checkpoint after `iteration` iterations goes.
    pub fn checkpoint(&self, iteration: usize) -> PathBuf {
        checkpoint_path(&self.dir, iteration)
    }
}

/// Takes the run folder's lock (`dir/.lock`, released by the OS when the process ends).
fn lock(dir: &Path) -> Result<std::fs::File, TrainError> {
    match flapper_files::lock_folder(dir) {
        Ok(Some(file)) => Ok(file),
        Ok(None) => Err(TrainError::Busy(dir.to_owned())),
        Err(e) => Err(TrainError::Output { path: dir.join(".lock"), message: e.to_string() }),
    }
}

pub fn checkpoint_dir(dir: &Path) -> PathBuf {
    dir.join("checkpoints")
}

/// `dir/checkpoints/iter_NNNNNN.safetensors`.
pub fn checkpoint_path(dir: &Path, iteration: usize) -> PathBuf {
    checkpoint_dir(dir).join(format!("iter_{iteration:06}.safetensors"))
}

/// Every `iter_NNNNNN.safetensors` in the run's checkpoint folder with its iteration, oldest first.
pub fn saved_checkpoints(dir: &Path) -> Vec<(usize, PathBuf)> {
    let Ok(entries) = std::fs::read_dir(checkpoint_dir(dir)) else { return Vec::new() };
    let mut found: Vec<(usize, PathBuf)> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter_map(|p| {
            let name = p.file_name()?.to_str()?;
            let number: usize = name.strip_prefix("iter_")?.strip_suffix(".safetensors")?.parse().ok()?;
            Some((number, p))
        })
        .collect();
    found.sort();
    found
}

/// The newest `iter_NNNNNN.safetensors` in the run's checkpoint folder.
pub fn latest_checkpoint(dir: &Path) -> Option<PathBuf> {
    saved_checkpoints(dir).pop().map(|(_, p)| p)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An empty folder of this test's own under the system's temporary folder.
    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("flapper-run-folder-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn checkpoints_are_listed_by_iteration_and_other_files_ignored() {
        let dir = scratch("listing");
        std::fs::create_dir_all(checkpoint_dir(&dir)).unwrap();
        for name in ["iter_000200.safetensors", "iter_000010.safetensors", "iter_000010.safetensors.json", "notes.txt"]
        {
            std::fs::write(checkpoint_dir(&dir).join(name), "").unwrap();
        }
        let listed: Vec<usize> = saved_checkpoints(&dir).into_iter().map(|(i, _)| i).collect();
        assert_eq!(listed, [10, 200]);
        assert_eq!(latest_checkpoint(&dir), Some(checkpoint_path(&dir, 200)));
    }

    #[test]
    fn a_new_run_refuses_a_folder_with_a_run_or_a_file_it_would_write() {
        let dir = scratch("refusals");
        std::fs::write(dir.join("learning_curves.svg"), "mine").unwrap();
        let refused = RunFolder::create(&dir, "").unwrap_err();
        assert!(matches!(refused, TrainError::WouldOverwrite { file: "learning_curves.svg", .. }), "{refused}");
        assert_eq!(std::fs::read_to_string(dir.join("learning_curves.svg")).unwrap(), "mine");

        let run = dir.join("run");
        let folder = RunFolder::create(&run, "seed = 3\n").unwrap();
        assert_eq!(std::fs::read_to_string(run.join("config.toml")).unwrap(), "seed = 3\n");
        let early = RunFolder::open(&run).unwrap_err();
        assert!(matches!(early, TrainError::Busy(_)), "busy before the first checkpoint too: {early}");
        std::fs::write(folder.checkpoint(5), "").unwrap();
        assert!(matches!(RunFolder::open(&run).unwrap_err(), TrainError::Busy(_)), "the first owner holds the lock");
        drop(folder);
        let empty = dir.join("empty");
        RunFolder::create(&empty, "").map(drop).unwrap();
        assert!(matches!(RunFolder::open(&empty).unwrap_err(), TrainError::NothingToResume(_)));
        let not_a_run = scratch("not-a-run");
        assert!(matches!(RunFolder::open(&not_a_run).unwrap_err(), TrainError::NothingToResume(_)));
        assert!(!not_a_run.join(".lock").exists(), "no lock file left in a folder that is no run");
        assert!(matches!(RunFolder::create(&run, "").unwrap_err(), TrainError::RunExists(_)));
        let (_, newest) = RunFolder::open(&run).unwrap();
        assert_eq!(newest, checkpoint_path(&run, 5));
    }
}
