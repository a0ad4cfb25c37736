//! A training run's configuration in one TOML file: `[runner]` (environments, iterations, seed,
//! checkpoints), `[ppo]` (the learner) and `[task]` (the flight task; `stage = 1..4` picks the
//! curriculum preset, every other key overrides it). Every key is optional; unknown keys are errors.

use std::path::Path;

use flapper_ppo::config::InvalidSetting;
use flapper_ppo::{PpoConfig, RunnerConfig};
use flapper_task::TaskConfig;
use flapper_task::config::ConfigError;
use serde::{Deserialize, Serialize};

#[derive(Debug, thiserror::Error)]
pub enum TrainConfigError {
    #[error("cannot read config '{path}': {source}")]
    Read { path: String, source: std::io::Error },
    #[error("config '{path}': {message}")]
    Parse { path: String, message: String },
    #[error("config '{path}', [task]: {}", error.detail())]
    Task { path: String, error: ConfigError },
    #[error("config '{path}': {source}")]
    Invalid { path: String, source: InvalidSetting },
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    pub runner: RunnerConfig,
    pub ppo: PpoConfig,
    pub task: TaskConfig,
}

/// The learner's half of the file; `task` is read by the task's own loader.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LearnerTables {
    #[serde(default)]
    runner: RunnerConfig,
    #[serde(default)]
    ppo: PpoConfig,
    #[serde(default)]
    #[allow(dead_code)]
    task: Option<toml::Table>,
}

impl TrainConfig {
    /// Reads `path`; `stage`, when given, replaces the file's `task.stage`.
    pub fn load(path: &Path, stage: Option<i64>) -> Result<Self, TrainConfigError> {
        let text = std::fs::read_to_string(path)
            .map_err(|source| TrainConfigError::Read { path: path.display().to_string(), source })?;
        Self::from_toml(&text, &path.display().to_string(), stage)
    }

    /// As [`TrainConfig::load`], from text; `origin` names it in errors.
    pub fn from_toml(text: &str, origin: &str, stage: Option<i64>) -> Result<Self, TrainConfigError> {
        let parse = |message: String| TrainConfigError::Parse { path: origin.to_owned(), message };
        let mut table: toml::Table = text.parse().map_err(|e: toml::de::Error| parse(e.to_string()))?;
        let learner: LearnerTables =
            toml::Value::Table(table.clone()).try_into().map_err(|e: toml::de::Error| parse(e.to_string()))?;
        let mut task_table = match table.remove("task") {
            Some(toml::Value::Table(t)) => t,
            Some(_) => return Err(parse("[task] must be a table".into())),
            None => toml::Table::new(),
        };
        if let Some(stage) = stage {
            task_table.insert("stage".into(), toml::Value::Integer(stage));
        }
        let task = TaskConfig::from_toml(&toml::to_string(&task_table).map_err(|e| parse(e.to_string()))?, origin)
            .map_err(|error| TrainConfigError::Task { path: origin.to_owned(), error })?;
        let invalid = |source| TrainConfigError::Invalid { path: origin.to_owned(), source };
        learner.ppo.validate().map_err(invalid)?;
        let action_names = flapper_sim::ActuatedJoint::ALL.map(|joint| joint.name());
        learner.ppo.validate_for_actions(&action_names).map_err(invalid)?;
        learner.runner.validate(&learner.ppo).map_err(invalid)?;
        Ok(Self { runner: learner.runner, ppo: learner.ppo, task })
    }

    /// The whole configuration, every value written out, as TOML (saved with the run and its files).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("the config serializes")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_empty_file_gives_the_paper_and_rsl_rl_defaults() {
        let c = TrainConfig::from_toml("", "empty.toml", None).unwrap();
        assert_eq!(c.ppo, PpoConfig::default());
        assert_eq!(c.runner, RunnerConfig::default());
        assert_eq!(c.task, TaskConfig::default());
        assert_eq!((c.ppo.steps_per_env, c.ppo.epochs, c.ppo.minibatches, c.ppo.clip), (24, 5, 4, 0.2));
        assert_eq!((c.ppo.gamma, c.ppo.lambda, c.ppo.desired_kl, c.runner.envs), (0.99, 0.95, 0.01, 256));
    }

    #[test]
    fn written_config_reads_back_identically_and_stage_overrides() {
        let c = TrainConfig::from_toml(
            "[runner]\niterations = 7\n[task]\nstage = 2\n[task.reward]\nposition_scale_m = 0.7\n",
            "a.toml",
            None,
        )
        .unwrap();
        assert_eq!(c.runner.iterations, 7);
        assert_eq!(c.task.stage, 2);
        let again = TrainConfig::from_toml(&c.to_toml(), "b.toml", None).unwrap();
        assert_eq!(again, c);
        assert!(!c.to_toml().contains("smoothness_norm"), "the default norm is left out of a written config");
        assert!(!c.to_toml().contains("smoothness_action_scale"), "so are the default shares");
        for key in ["flap_rate", "flap_max_hz", "glide_hold", "clock_hz", "feathering"] {
            assert!(
                !c.to_toml().contains(key),
                "{key}: the flap's, the glide's, the clock's and the feathering's keys at their defaults too"
            );
        }
        let glide = "[task.reward]\nglide_hold_weight = 0.3\nglide_hold_scale_deg = 15\nflap_rate_weight = 0.1\n\
                     feathering_weight = 0.2\n[task.observation]\nclock_hz = 5.3\n\
                     [task.control]\npassive_feathering_s = 0.03\n";
        let glide = TrainConfig::from_toml(glide, "g.toml", None).unwrap();
        assert_eq!((glide.task.reward.glide_hold_weight, glide.task.reward.glide_hold_scale_deg), (0.3, 15.0));
        assert_eq!(glide.task.observation.clock_hz, 5.3);
        assert_eq!((glide.task.reward.feathering_weight, glide.task.control.passive_feathering_s), (0.2, 0.03));
        assert_eq!(TrainConfig::from_toml(&glide.to_toml(), "g2.toml", None).unwrap(), glide);
        let euclidean = TrainConfig::from_toml("[ppo]\nsmoothness_norm = \"euclidean\"\n", "e.toml", None).unwrap();
        assert_eq!(euclidean.ppo.smoothness_norm, flapper_ppo::config::SmoothnessNorm::Euclidean);
        assert_eq!(TrainConfig::from_toml(&euclidean.to_toml(), "e2.toml", None).unwrap(), euclidean);
        let staged = TrainConfig::from_toml(&c.to_toml(), "b.toml", Some(1)).unwrap();
        assert_eq!(staged.task.stage, 1);
        assert_eq!(staged.task.reward.position_scale_m, 0.7, "the file's overrides stay");
    }

    #[test]
    fn unknown_keys_and_bad_values_are_named_with_the_file() {
        let err = |text: &str| TrainConfig::from_toml(text, "bad.toml", None).unwrap_err().to_string();
        let e = err("[ppo]\ncliip = 0.2\n");
        assert!(e.contains("bad.toml") && e.contains("cliip"), "{e}");
        let e = err("[trainer]\nx = 1\n");
        assert!(e.contains("trainer"), "{e}");
        let e = err("[ppo]\ngamma = 1.5\n");
        assert!(e.contains("ppo.gamma") && e.contains("1.5"), "{e}");
        let e = err("[runner]\nenvs = 0\n");
        assert!(e.contains("runner.envs"), "{e}");
        let e = err("[task.reward]\nposition_wieght = 1.0\n");
        assert!(e.contains("bad.toml") && e.contains("position_wieght"), "{e}");
        let e = err("[ppo]\nactivation = \"sigmoid\"\n");
        assert!(e.contains("sigmoid"), "{e}");
        let e = err("[ppo]\nsmoothness_norm = \"manhattan\"\n");
        assert!(e.contains("bad.toml") && e.contains("manhattan") && e.contains("euclidean"), "{e}");
        let e = err("[ppo]\nsmoothness_action_scale = [1.0, 0.0, 1.0]\n");
        assert!(e.contains("bad.toml") && e.contains("smoothness_action_scale") && e.contains("3 shares"), "{e}");
        assert!(e.contains("flap_left, pitch_left, flap_right, pitch_right, tail_pitch"), "{e}");
        let e = err("[ppo]\nsmoothness_action_scale = [1.0, -1.0, 1.0, 0.0, 0.0]\n");
        assert!(e.contains("smoothness_action_scale") && e.contains("-1"), "{e}");
        let shares = TrainConfig::from_toml("[ppo]\nsmoothness_action_scale = [1, 0, 1, 0, 0.5]\n", "s.toml", None);
        let shares = shares.unwrap();
        assert_eq!(shares.ppo.smoothness_action_scale, vec![1.0, 0.0, 1.0, 0.0, 0.5]);
        assert_eq!(TrainConfig::from_toml(&shares.to_toml(), "s2.toml", None).unwrap(), shares);
        let e = err("[ppo]\ncurvature_coef = -0.1\n");
        assert!(e.contains("bad.toml") && e.contains("ppo.curvature_coef") && e.contains("-0.1"), "{e}");
        // Written only when on: a config without it writes and reads as before.
        assert!(!shares.to_toml().contains("curvature_coef"));
        let bent = TrainConfig::from_toml("[ppo]\ncurvature_coef = 0.1\n", "c.toml", None).unwrap();
        assert_eq!(TrainConfig::from_toml(&bent.to_toml(), "c2.toml", None).unwrap(), bent);
        assert!(TrainConfig::from_toml("", "x.toml", Some(7)).unwrap_err().to_string().contains("stage 7"));
    }
}
