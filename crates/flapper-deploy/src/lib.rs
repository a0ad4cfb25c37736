//! The trained controller leaving flapper (docs/deploy.md): the last box of the flow, after the policy
//! file. A robot needs the policy's arithmetic and the facts around it.
//!
//! - `facts`: what a robot must know to build the policy's input and use its output (observation
//!   layout, joints and their ranges, control rate, filter cutoff), read from the policy's task and the
//!   robot model, written once for every export (ONNX metadata, C header);
//! - `c_source`: the policy as one C99 header and source file (weights as `static const float`, one
//!   function, no allocation, only `math.h`), the same bits as flapper's own inference;
//! - `c_compiler`: the system C compiler, to time the exported C (and to test it).
//!
//! ONNX is written by the Python package with the `onnx` library (`flapper.Policy.export_onnx`), from
//! the same facts and the same [`PolicyArrays`].

pub mod c_compiler;
pub mod c_source;
pub mod facts;

use std::path::{Path, PathBuf};

use flapper_eval::{FlightPolicyFile, PolicyFileError, load_flight_policy_file};
use flapper_ppo::ActorCritic;
use flapper_ppo::mlp::Activation;
use flapper_ppo::normalizer::{CLIP, EPSILON};
use flapper_sim::{ModelError, RobotModel};

pub use facts::DeploymentFacts;

#[derive(Debug, thiserror::Error)]
pub enum DeployError {
    #[error(transparent)]
    PolicyFile(#[from] PolicyFileError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("'{path}' exists; choose another name (nothing is overwritten)")]
    Exists { path: PathBuf },
    #[error("cannot write '{path}': {source}")]
    Write { path: PathBuf, source: std::io::Error },
    #[error("--out '{path}': {why}")]
    OutName { path: PathBuf, why: &'static str },
    #[error("{0}")]
    Compiler(String),
    #[error(
        "'{path}' reads a {clock_hz} Hz clock (`[task.observation] clock_hz`), which the exports do not carry yet; \
         export a policy trained without it"
    )]
    Clock { path: PathBuf, clock_hz: f64 },
}

/// One dense layer of the actor: `out = weight x in + bias`, `weight` row-major [fan_out x fan_in]
/// (PyTorch's `nn.Linear` layout).
#[derive(Debug, Clone, PartialEq)]
pub struct DenseLayer {
    pub fan_in: usize,
    pub fan_out: usize,
    pub weight: Vec<f32>,
    pub bias: Vec<f32>,
}

/// The numbers of a policy's deterministic action, in f32 as flapper applies them: normalize each
/// feature (`clamp((x - mean) * scale, -clip, clip)`), the dense layers with `activation` between them
/// (none after the last), and the environment's clip of the action to [-1, 1].
#[derive(Debug, Clone, PartialEq)]
pub struct PolicyArrays {
    pub normalizer_mean: Vec<f32>,
    /// 1 / (sqrt(variance) + epsilon), rounded to f32 from f64 as the normalizer does.
    pub normalizer_scale: Vec<f32>,
    pub normalizer_epsilon: f64,
    pub normalizer_clip: f32,
    pub layers: Vec<DenseLayer>,
    pub activation: Activation,
}

impl PolicyArrays {
    pub fn of(policy: &ActorCritic) -> Self {
        let normalizer = &policy.normalizer;
        let (normalizer_mean, normalizer_scale) = (0..normalizer.size()).map(|i| normalizer.frozen_feature(i)).unzip();
        let actor = &policy.actor;
        let layers = actor
            .sizes()
            .windows(2)
            .zip(actor.tensors().chunks_exact(2))
            .map(|(sizes, pair)| DenseLayer {
                fan_in: sizes[0],
                fan_out: sizes[1],
                weight: actor.params()[pair[0].range.clone()].to_vec(),
                bias: actor.params()[pair[1].range.clone()].to_vec(),
            })
            .collect();
        Self {
            normalizer_mean,
            normalizer_scale,
            normalizer_epsilon: EPSILON,
            normalizer_clip: CLIP,
            layers,
            activation: policy.activation(),
        }
    }

    pub fn observation_size(&self) -> usize {
        self.normalizer_mean.len()
    }

    pub fn action_size(&self) -> usize {
        self.layers.last().map_or(0, |l| l.fan_out)
    }

    /// Multiplications (each followed by an addition) of one action: the dense layers' weights.
    pub fn multiply_adds(&self) -> usize {
        self.layers.iter().map(|l| l.fan_in * l.fan_out).sum()
    }

    /// Bytes of the numbers an export holds (float32): normalizer mean and scale, weights and biases.
    pub fn weight_bytes(&self) -> usize {
        let floats: usize =
            2 * self.observation_size() + self.layers.iter().map(|l| l.weight.len() + l.bias.len()).sum::<usize>();
        floats * size_of::<f32>()
    }
}

/// A policy ready to leave flapper: its arithmetic and the facts around it.
#[derive(Debug, Clone)]
pub struct DeployablePolicy {
    pub arrays: PolicyArrays,
    pub facts: DeploymentFacts,
    /// The policy as flapper flies it (for checks against an export).
    pub policy: ActorCritic,
}

impl DeployablePolicy {
    /// Reads a policy file or a checkpoint (refused with one line if it is neither) and the facts of its
    /// task on `robot`.
    pub fn load(path: &Path, robot: &RobotModel) -> Result<Self, DeployError> {
        let file = load_flight_policy_file(path)?;
        Self::of(&file, path, robot)
    }

    pub fn of(file: &FlightPolicyFile, path: &Path, robot: &RobotModel) -> Result<Self, DeployError> {
        let arrays = PolicyArrays::of(&file.policy);
        let facts = DeploymentFacts::of(file, path, &arrays, robot)?;
        Ok(Self { arrays, facts, policy: file.policy.clone() })
    }
}

/// Refuses an output path that exists (nothing is overwritten).
pub fn refuse_existing(path: &Path) -> Result<(), DeployError> {
    if path.exists() { Err(DeployError::Exists { path: path.to_owned() }) } else { Ok(()) }
}

/// The two files `--format c` writes for `out` (`NAME.c`): the source and its header `NAME.h` beside it.
pub fn c_file_pair(out: &Path) -> Result<(PathBuf, PathBuf), DeployError> {
    if out.extension().and_then(|e| e.to_str()) != Some("c") || out.file_stem().is_none() {
        return Err(DeployError::OutName {
            path: out.to_owned(),
            why: "a C export names its source file NAME.c (the header NAME.h is written beside it)",
        });
    }
    Ok((out.to_owned(), out.with_extension("h")))
}

/// Writes the policy as `out` (NAME.c) and NAME.h beside it, neither of which may exist. Returns the
/// header's path.
pub fn write_c_source(policy: &DeployablePolicy, out: &Path) -> Result<PathBuf, DeployError> {
    let (source_path, header_path) = c_file_pair(out)?;
    refuse_existing(&source_path)?;
    refuse_existing(&header_path)?;
    let stem = source_path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let text = c_source::c_source(&policy.arrays, &policy.facts, &stem);
    let write = |path: &Path, text: &str| {
        flapper_files::write_atomically(path, text.as_bytes())
            .map_err(|source| DeployError::Write { path: path.to_owned(), source })
    };
    write(&header_path, &text.header)?;
    write(&source_path, &text.source)?;
    Ok(header_path)
}
