//! The learner: PPO (Schulman et al. 2017) on the CPU. It drives any [`vec_env::VecEnv`] and knows
//! nothing of wings. The flow of one iteration, file by file:
//!
//! - `vec_env`: the interface every batch of environments implements;
//! - `normalizer`, `actor_critic`: the policy (observation statistics, actor, log-std, critic), built
//!   on `mlp` (forward and backward by hand on `fixed_matmul`, one arithmetic on every CPU, `fast_math` for
//!   the activations; `normal` for the exploration noise);
//!   `exact_inference`: the CPU-independent forward pass that flies a trained policy;
//! - `storage`: the rollout and its generalized advantages;
//! - `ppo`: acting, bootstrapping truncated episodes, the update (`loss`: the clipped loss and its
//!   gradients), `adam`;
//! - `runner`: iterations, `training_log` (the CSV), `checkpoint`s, checkpoint hooks, in a
//!   `run_folder` (its files, its lock, what a new run refuses); `config`: every setting, rsl_rl's
//!   defaults. Nothing here draws: the training crate plots learning curves.

pub mod actor_critic;
pub mod adam;
pub mod benchmark;
pub mod checkpoint;
pub mod config;
pub mod evaluate;
pub mod exact_inference;
pub mod fast_math;
pub mod fixed_matmul;
pub mod loss;
pub mod mlp;
pub mod normal;
pub mod normalizer;
pub mod ppo;
pub mod run_folder;
pub mod runner;
pub mod storage;
pub mod train_error;
pub mod training_log;
pub mod vec_env;

pub use actor_critic::{ActorCritic, InferenceScratch};
pub use config::{PpoConfig, RunnerConfig, Schedule};
pub use runner::{CheckpointEvent, CheckpointHook, IterationLog, Start, TrainError, Trainer};
pub use vec_env::{EndReason, EnvError, EpisodeRecord, VecEnv};
