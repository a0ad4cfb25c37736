//! Loading a trained flight policy for flying it: the networks from the file, and the task it was
//! trained on from the config saved inside (only its `[task]` table: evaluation needs nothing of the
//! learner's settings, so evaluation does not depend on the training crate).

use std::path::Path;

use flapper_ppo::ActorCritic;
use flapper_ppo::checkpoint::{self, CheckpointError, CheckpointInfo};
use flapper_task::TaskConfig;
use flapper_task::config::ConfigError;

#[derive(Debug, thiserror::Error)]
pub enum PolicyFileError {
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error("config '{origin}': {message}")]
    Parse { origin: String, message: String },
    #[error("config '{origin}', [task]: {}", error.detail())]
    Task { origin: String, error: ConfigError },
}

/// A trained flight policy (a policy file or a checkpoint) and the task it was trained on, checked to
/// fit that task's observation and action layout.
pub fn load_flight_policy(path: &Path) -> Result<(ActorCritic, TaskConfig), PolicyFileError> {
    let FlightPolicyFile { policy, task, .. } = load_flight_policy_file(path)?;
    Ok((policy, task))
}

/// A flight policy as read from its file, with the file's description.
#[derive(Debug, Clone)]
pub struct FlightPolicyFile {
    pub policy: ActorCritic,
    pub task: TaskConfig,
    /// What the file is (a policy, or a checkpoint of a run), its iteration and environment steps.
    pub info: CheckpointInfo,
}

/// As [`load_flight_policy`], keeping the file's description (what an export tells about its source).
pub fn load_flight_policy_file(path: &Path) -> Result<FlightPolicyFile, PolicyFileError> {
    let loaded = checkpoint::load(path)?;
    let origin = format!("{} (its saved config)", path.display());
    let parse = |message: String| PolicyFileError::Parse { origin: origin.clone(), message };
    let mut saved: toml::Table = loaded.info.config_toml.parse().map_err(|e: toml::de::Error| parse(e.to_string()))?;
    let task_table = match saved.remove("task") {
        Some(toml::Value::Table(t)) => t,
        Some(_) => return Err(parse("[task] must be a table".into())),
        None => toml::Table::new(),
    };
    let text = toml::to_string(&task_table).map_err(|e| parse(e.to_string()))?;
    let task = TaskConfig::from_toml(&text, &origin)
        .map_err(|error| PolicyFileError::Task { origin: origin.clone(), error })?;
    let layout = flapper_task::observation::ObservationLayout::of(&task.observation);
    loaded.check_layout(path, layout.size(), flapper_task::action::ACTION_SIZE)?;
    Ok(FlightPolicyFile { policy: loaded.policy, task, info: loaded.info })
}
