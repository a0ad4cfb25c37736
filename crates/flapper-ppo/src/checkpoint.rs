//! Checkpoints and policy files as safetensors (the weights load in PyTorch: `actor.0.weight` is an
//! `nn.Linear` weight [out, in]) with a JSON description in the file's metadata and beside it
//! (`<file>.json`). Files are written to a temporary name and renamed, so a killed run never leaves a
//! half-written one.
//!
//! A checkpoint holds everything a run needs to continue exactly: both networks, the log-std, the
//! normalizer statistics, Adam's moments, the learning rate, the learner's random state, the
//! iteration counter, the full config and the environments' state (every episode as it stands, so
//! that a resumed run does not restart them). A policy file holds the networks and normalizer only.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use safetensors::tensor::{Dtype, SafeTensors, TensorView};
use serde::{Deserialize, Serialize};

use crate::actor_critic::ActorCritic;
use crate::adam::Adam;
use crate::mlp::{Activation, Mlp};
use crate::normalizer::Normalizer;
use crate::ppo::{Optimizer, Ppo};

/// Bumped when the file layout changes.
pub const FORMAT_VERSION: u32 = 1;
const METADATA_KEY: &str = "flapper";
const ENVIRONMENTS_TENSOR: &str = "environments.state";

#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("cannot read '{path}': {source}")]
    Read { path: PathBuf, source: std::io::Error },
    #[error("cannot write '{path}': {source}")]
    Write { path: PathBuf, source: std::io::Error },
    #[error("'{path}' is not a flapper policy or checkpoint ({message}); was it truncated or written by another tool?")]
    Format { path: PathBuf, message: String },
    #[error("'{path}' was trained for {found}, but this run has {expected}")]
    Layout { path: PathBuf, found: String, expected: String },
    #[error("'{path}' exists; choose another name (nothing is overwritten)")]
    Exists { path: PathBuf },
}

/// The learner's random stream, as ChaCha8 describes its position.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct RngState {
    pub seed_hex: String,
    pub stream: u64,
    /// u128 as a decimal string (JSON numbers stop at 2^53).
    pub word_pos: String,
}

impl RngState {
    pub fn capture(rng: &ChaCha8Rng) -> Self {
        Self {
            seed_hex: rng.get_seed().iter().map(|b| format!("{b:02x}")).collect(),
            stream: rng.get_stream(),
            word_pos: rng.get_word_pos().to_string(),
        }
    }

    pub fn restore(&self) -> Option<ChaCha8Rng> {
        if self.seed_hex.len() != 64 {
            return None;
        }
        let mut seed = [0u8; 32];
        for (i, byte) in seed.iter_mut().enumerate() {
            *byte = u8::from_str_radix(self.seed_hex.get(2 * i..2 * i + 2)?, 16).ok()?;
        }
        let mut rng = ChaCha8Rng::from_seed(seed);
        rng.set_stream(self.stream);
        rng.set_word_pos(self.word_pos.parse().ok()?);
        Some(rng)
    }
}

/// What a file can do: resume a run, or only fly.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CheckpointKind {
    /// Networks, optimizer, random streams and environments: resumes a run exactly.
    Checkpoint,
    /// Networks and normalizer only: flies, evaluates, starts a new run.
    Policy,
}

/// The description stored in the file's metadata and in the `.json` beside it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CheckpointInfo {
    pub format_version: u32,
    /// Stored as "checkpoint" or "policy".
    pub kind: CheckpointKind,
    /// Iterations completed.
    pub iteration: usize,
    pub env_steps: u64,
    /// Training wall time so far, over all sessions.
    pub wall_time_s: f64,
    pub observation_size: usize,
    pub action_size: usize,
    pub actor_sizes: Vec<usize>,
    pub critic_sizes: Vec<usize>,
    pub activation: Activation,
    pub learning_rate: f32,
    pub adam_steps: u64,
    pub rng: Option<RngState>,
    /// The run's full configuration (TOML), so the file says how it was made.
    pub config_toml: String,
}

/// What a file holds once read.
#[derive(Debug, Clone)]
pub struct Checkpoint {
    pub info: CheckpointInfo,
    pub policy: ActorCritic,
    /// Present in checkpoints, absent in policy files.
    pub optimizer: Option<Optimizer>,
    /// The environments' state ([`crate::VecEnv::save_state`]); present in checkpoints.
    pub environments: Option<Vec<u8>>,
}

impl Checkpoint {
    /// Rejects a file whose networks do not fit `observation_size` inputs and `action_size` outputs.
    pub fn check_layout(
        &self,
        path: &Path,
        observation_size: usize,
        action_size: usize,
    ) -> Result<(), CheckpointError> {
        let (o, a) = (self.info.observation_size, self.info.action_size);
        if (o, a) != (observation_size, action_size) {
            return Err(CheckpointError::Layout {
                path: path.to_owned(),
                found: format!("{o} observations and {a} actions"),
                expected: format!("{observation_size} observations and {action_size} actions"),
            });
        }
        Ok(())
    }

    /// This file's learner given `extra` more observations after its own ([`ActorCritic::with_inputs_appended`]),
    /// its Adam moments for the new weights 0.
    pub fn with_inputs_appended(self, extra: usize) -> Self {
        let policy = self.policy.with_inputs_appended(extra);
        let optimizer = self.optimizer.map(|mut optimizer| {
            for (adam, mlp) in
                [(&mut optimizer.actor, &self.policy.actor), (&mut optimizer.critic, &self.policy.critic)]
            {
                adam.first_moment = mlp.values_with_inputs_appended(&adam.first_moment, extra);
                adam.second_moment = mlp.values_with_inputs_appended(&adam.second_moment, extra);
            }
            optimizer
        });
        let info = CheckpointInfo {
            observation_size: self.info.observation_size + extra,
            actor_sizes: policy.actor.sizes().to_vec(),
            critic_sizes: policy.critic.sizes().to_vec(),
            ..self.info
        };
        Self { info, policy, optimizer, environments: self.environments }
    }

    /// The learner's random stream as saved.
    pub fn rng(&self) -> Option<ChaCha8Rng> {
        self.info.rng.as_ref().and_then(RngState::restore)
    }
}

/// Describes `ppo` for a file of `kind`.
pub fn describe(
    ppo: &Ppo,
    kind: CheckpointKind,
    iteration: usize,
    env_steps: u64,
    wall_time_s: f64,
    config_toml: &str,
) -> CheckpointInfo {
    let policy = &ppo.policy;
    CheckpointInfo {
        format_version: FORMAT_VERSION,
        kind,
        iteration,
        env_steps,
        wall_time_s,
        observation_size: policy.observation_size(),
        action_size: policy.action_size(),
        actor_sizes: policy.actor.sizes().to_vec(),
        critic_sizes: policy.critic.sizes().to_vec(),
        activation: policy.activation(),
        learning_rate: ppo.learning_rate,
        adam_steps: ppo.optimizer.actor.steps,
        rng: (kind == CheckpointKind::Checkpoint).then(|| RngState::capture(&ppo.rng)),
        config_toml: config_toml.to_owned(),
    }
}

/// Writes `policy` (and `optimizer`, for a resumable checkpoint) to `path` atomically, and the
/// description to `path.json`.
/// `environments` (for a checkpoint) is stored as one byte tensor, `environments.state`.
pub fn save(
    path: &Path,
    info: &CheckpointInfo,
    policy: &ActorCritic,
    optimizer: Option<&Optimizer>,
    environments: Option<&[u8]>,
) -> Result<(), CheckpointError> {
    let mut tensors: Vec<(String, Dtype, Vec<usize>, Vec<u8>)> = Vec::new();
    let mut f32s = |name: String, shape: Vec<usize>, values: &[f32]| {
        tensors.push((name, Dtype::F32, shape, values.iter().flat_map(|v| v.to_le_bytes()).collect()));
    };
    for (prefix, net) in [("actor", &policy.actor), ("critic", &policy.critic)] {
        for t in net.tensors() {
            f32s(format!("{prefix}.{}", t.name), t.shape.clone(), &net.params()[t.range.clone()]);
        }
    }
    f32s("actor.log_std".into(), vec![policy.log_std.len()], &policy.log_std);
    if let Some(o) = optimizer {
        for (name, adam) in [("actor", &o.actor), ("critic", &o.critic), ("log_std", &o.log_std)] {
            f32s(format!("optimizer.{name}.exp_avg"), vec![adam.first_moment.len()], &adam.first_moment);
            f32s(format!("optimizer.{name}.exp_avg_sq"), vec![adam.second_moment.len()], &adam.second_moment);
        }
    }
    let n = &policy.normalizer;
    let f64s = |values: &[f64]| values.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>();
    tensors.push(("normalizer.mean".into(), Dtype::F64, vec![n.size()], f64s(&n.mean)));
    tensors.push(("normalizer.variance".into(), Dtype::F64, vec![n.size()], f64s(&n.variance)));
    tensors.push(("normalizer.count".into(), Dtype::F64, vec![1], f64s(&[n.count])));
    if let Some(state) = environments {
        tensors.push((ENVIRONMENTS_TENSOR.into(), Dtype::U8, vec![state.len()], state.to_vec()));
    }

    let json = serde_json::to_string_pretty(info).expect("the description serializes");
    let views = tensors
        .iter()
        .map(|(name, dtype, shape, bytes)| {
            let view = TensorView::new(*dtype, shape.clone(), bytes).expect("shape matches the data");
            (name.clone(), view)
        })
        .collect::<Vec<_>>();
    let metadata = HashMap::from([(METADATA_KEY.to_owned(), json.clone())]);
    let bytes = safetensors::serialize(views, Some(metadata))
        .map_err(|e| CheckpointError::Write { path: path.to_owned(), source: std::io::Error::other(e.to_string()) })?;
    write_atomically(path, &bytes)?;
    write_atomically(&sidecar_path(path), json.as_bytes())
}

/// `<file>.json`.
pub fn sidecar_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".json");
    PathBuf::from(name)
}

/// Writes `bytes` to `path` whole or not at all ([`flapper_files::write_atomically`]).
pub fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), CheckpointError> {
    flapper_files::write_atomically(path, bytes)
        .map_err(|source| CheckpointError::Write { path: path.to_owned(), source })
}

/// Writes the networks of the checkpoint (or policy) at `from` as a policy file at `to`, which must
/// not exist: the shipped `policy.safetensors` of a chosen iteration. Returns its description.
pub fn export_policy(from: &Path, to: &Path) -> Result<CheckpointInfo, CheckpointError> {
    if to.exists() {
        return Err(CheckpointError::Exists { path: to.to_owned() });
    }
    let loaded = load(from)?;
    let info = CheckpointInfo { kind: CheckpointKind::Policy, rng: None, ..loaded.info };
    save(to, &info, &loaded.policy, None, None)?;
    Ok(info)
}

/// Writes the mean of the networks of `from` (checkpoints or policies of one run, oldest first) as a
/// policy file at `to`, which must not exist: every weight, bias and log-std averaged (summed in the
/// order given, in f64), the normalizer and the description of the newest. Averaging the weights of
/// neighbouring checkpoints of a fine-tuning run smooths the checkpoint-to-checkpoint swings that a
/// small learning rate leaves (stochastic weight averaging; docs/training.md). Files whose networks
/// differ in layout are refused.
pub fn export_average_policy(from: &[PathBuf], to: &Path) -> Result<CheckpointInfo, CheckpointError> {
    if from.is_empty() {
        return Err(CheckpointError::Format { path: to.to_owned(), message: "no checkpoint to average".into() });
    }
    if to.exists() {
        return Err(CheckpointError::Exists { path: to.to_owned() });
    }
    let mut sums: Vec<Vec<f64>> = Vec::new();
    let mut first: Option<(&PathBuf, String)> = None;
    let mut newest = None;
    for path in from {
        let loaded = load(path)?;
        let policy = &loaded.policy;
        let layout = format!("an actor of {:?} and a critic of {:?}", policy.actor.sizes(), policy.critic.sizes());
        let (first_path, expected) = first.get_or_insert_with(|| (path, layout.clone()));
        if layout != *expected {
            return Err(CheckpointError::Layout {
                path: path.clone(),
                found: layout,
                expected: format!("that of '{}': {expected}", first_path.display()),
            });
        }
        let values = [policy.actor.params(), policy.critic.params(), &policy.log_std[..]];
        sums.resize_with(values.len(), Vec::new);
        for (sum, values) in sums.iter_mut().zip(values) {
            sum.resize(values.len(), 0.0);
            for (s, v) in sum.iter_mut().zip(values) {
                *s += *v as f64;
            }
        }
        newest = Some(loaded);
    }
    let newest = newest.expect("at least one file was read");
    let count = from.len() as f64;
    let mut policy = newest.policy;
    let targets = [policy.actor.params_mut(), policy.critic.params_mut(), &mut policy.log_std[..]];
    for (target, sum) in targets.into_iter().zip(&sums) {
        for (t, s) in target.iter_mut().zip(sum) {
            *t = (s / count) as f32;
        }
    }
    let info = CheckpointInfo { kind: CheckpointKind::Policy, rng: None, ..newest.info };
    save(to, &info, &policy, None, None)?;
    Ok(info)
}

/// Reads a checkpoint or policy file, checking that every tensor is there with its shape.
pub fn load(path: &Path) -> Result<Checkpoint, CheckpointError> {
    let bytes = std::fs::read(path).map_err(|source| CheckpointError::Read { path: path.to_owned(), source })?;
    let format = |message: String| CheckpointError::Format { path: path.to_owned(), message };
    let (_, metadata) = SafeTensors::read_metadata(&bytes).map_err(|e| format(e.to_string()))?;
    let tensors = SafeTensors::deserialize(&bytes).map_err(|e| format(e.to_string()))?;
    let json = metadata
        .metadata()
        .as_ref()
        .and_then(|m| m.get(METADATA_KEY))
        .ok_or_else(|| format("no flapper description in its metadata".into()))?;
    let info: CheckpointInfo = serde_json::from_str(json).map_err(|e| format(e.to_string()))?;
    if info.format_version != FORMAT_VERSION {
        return Err(format(format!("format version {} (this build reads {FORMAT_VERSION})", info.format_version)));
    }
    if !(info.learning_rate.is_finite() && info.learning_rate > 0.0) {
        return Err(format(format!("learning rate {} (must be finite and positive)", info.learning_rate)));
    }
    let read = |name: &str, dtype: Dtype, len: usize| -> Result<Vec<u8>, CheckpointError> {
        let view = tensors.tensor(name).map_err(|_| format(format!("tensor '{name}' missing")))?;
        let count: usize = view.shape().iter().product();
        if view.dtype() != dtype || count != len {
            return Err(format(format!(
                "tensor '{name}' is {:?} {:?}, expected {dtype:?} of {len}",
                view.dtype(),
                view.shape()
            )));
        }
        Ok(view.data().to_vec())
    };
    let read_f32 = |name: &str, len: usize| -> Result<Vec<f32>, CheckpointError> {
        Ok(read(name, Dtype::F32, len)?.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect())
    };
    let read_f64 = |name: &str, len: usize| -> Result<Vec<f64>, CheckpointError> {
        Ok(read(name, Dtype::F64, len)?
            .chunks_exact(8)
            .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")))
            .collect())
    };
    let network = |prefix: &str, sizes: &[usize]| -> Result<Mlp, CheckpointError> {
        let shape_error = || format(format!("{prefix} sizes {sizes:?} are not a network"));
        let count = parameter_count(sizes).ok_or_else(shape_error)?;
        // Sizes come from the file's metadata: never allocate more than the file could hold.
        if count.saturating_mul(4) > bytes.len() {
            return Err(format(format!(
                "{prefix} declares {count} parameters, more than its {} bytes can hold",
                bytes.len()
            )));
        }
        let template = Mlp::with_params(sizes, info.activation, vec![0.0; count]).ok_or_else(shape_error)?;
        let mut params = vec![0.0; template.params().len()];
        for t in template.tensors() {
            let name = format!("{prefix}.{}", t.name);
            // The shape, not only the count: a transposed [in, out] weight has the same count.
            if let Ok(view) = tensors.tensor(&name)
                && view.shape() != t.shape.as_slice()
            {
                return Err(format(format!("tensor '{name}' has shape {:?}, expected {:?}", view.shape(), t.shape)));
            }
            params[t.range.clone()].copy_from_slice(&read_f32(&name, t.range.len())?);
        }
        Mlp::with_params(sizes, info.activation, params).ok_or_else(shape_error)
    };
    let actor = network("actor", &info.actor_sizes)?;
    let critic = network("critic", &info.critic_sizes)?;
    if actor.input_size() != info.observation_size
        || critic.input_size() != info.observation_size
        || actor.output_size() != info.action_size
        || critic.output_size() != 1
    {
        return Err(format("network sizes disagree with the observation and action sizes".into()));
    }
    let log_std = read_f32("actor.log_std", info.action_size)?;
    let o = info.observation_size;
    let normalizer = Normalizer {
        mean: read_f64("normalizer.mean", o)?,
        variance: read_f64("normalizer.variance", o)?,
        count: read_f64("normalizer.count", 1)?[0],
    };
    let optimizer = if info.kind == CheckpointKind::Checkpoint {
        let adam = |name: &str, len: usize| -> Result<Adam, CheckpointError> {
            let mut adam = Adam::new(len, info.learning_rate);
            adam.first_moment = read_f32(&format!("optimizer.{name}.exp_avg"), len)?;
            adam.second_moment = read_f32(&format!("optimizer.{name}.exp_avg_sq"), len)?;
            adam.steps = info.adam_steps;
            Ok(adam)
        };
        Some(Optimizer {
            actor: adam("actor", actor.params().len())?,
            critic: adam("critic", critic.params().len())?,
            log_std: adam("log_std", info.action_size)?,
        })
    } else {
        None
    };
    if info.kind == CheckpointKind::Checkpoint && info.rng.as_ref().and_then(RngState::restore).is_none() {
        return Err(format("checkpoint without a valid random state".into()));
    }
    let environments = match tensors.tensor(ENVIRONMENTS_TENSOR) {
        Ok(view) if view.dtype() == Dtype::U8 => Some(view.data().to_vec()),
        Ok(view) => return Err(format(format!("tensor '{ENVIRONMENTS_TENSOR}' is {:?}, expected U8", view.dtype()))),
        Err(_) => None,
    };
    let policy = ActorCritic { actor, critic, log_std, normalizer };
    check_values(path, &policy, optimizer.as_ref())?;
    Ok(Checkpoint { info, policy, optimizer, environments })
}

/// Refuses values a trained policy cannot hold: a file with them would fly or train on garbage.
fn check_values(path: &Path, policy: &ActorCritic, optimizer: Option<&Optimizer>) -> Result<(), CheckpointError> {
    let format = |message: String| CheckpointError::Format { path: path.to_owned(), message };
    let ActorCritic { actor, critic, log_std, normalizer } = policy;
    fn first_non_finite<T: Copy + Into<f64>>(values: &[T]) -> Option<usize> {
        values.iter().position(|&v| !v.into().is_finite())
    }
    let non_finite = |name: &str, found: Option<usize>| match found {
        Some(i) => Err(format(format!("tensor '{name}' holds a non-finite value (element {i})"))),
        None => Ok(()),
    };
    non_finite("actor", first_non_finite(actor.params()))?;
    non_finite("critic", first_non_finite(critic.params()))?;
    non_finite("actor.log_std", first_non_finite(log_std))?;
    if let Some(s) = log_std.iter().find(|s| !(-20.0..=5.0).contains(*s)) {
        return Err(format(format!("tensor 'actor.log_std' holds {s} (an action noise std outside [2e-9, 148])")));
    }
    non_finite("normalizer.mean", first_non_finite(&normalizer.mean))?;
    non_finite("normalizer.variance", first_non_finite(&normalizer.variance))?;
    if let Some(v) = normalizer.variance.iter().find(|v| **v < 0.0) {
        return Err(format(format!("tensor 'normalizer.variance' holds a negative variance {v}")));
    }
    if !(normalizer.count.is_finite() && normalizer.count >= 0.0) {
        return Err(format(format!(
            "tensor 'normalizer.count' is {} (must be finite and non-negative)",
            normalizer.count
        )));
    }
    if let Some(o) = optimizer {
        for (name, adam) in [("actor", &o.actor), ("critic", &o.critic), ("log_std", &o.log_std)] {
            non_finite(&format!("optimizer.{name}.exp_avg"), first_non_finite(&adam.first_moment))?;
            non_finite(&format!("optimizer.{name}.exp_avg_sq"), first_non_finite(&adam.second_moment))?;
            if adam.second_moment.iter().any(|v| *v < 0.0) {
                return Err(format(format!("tensor 'optimizer.{name}.exp_avg_sq' holds a negative value")));
            }
        }
    }
    Ok(())
}

fn parameter_count(sizes: &[usize]) -> Option<usize> {
    if sizes.len() < 2 || sizes.iter().any(|&s| s == 0 || s > 1 << 16) {
        return None;
    }
    Some(sizes.windows(2).map(|p| p[0] * p[1] + p[1]).sum())
}
