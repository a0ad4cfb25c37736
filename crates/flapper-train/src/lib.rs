//! Where environments meet the learner (between `task`/`vec_env` and `learner` in the flow): the
//! flight task as the learner's [`flapper_ppo::VecEnv`] (`flight_envs`), the inverted pendulum that
//! checks the learner on a known answer (`inverted_pendulum`), a run's TOML configuration (`config`),
//! and starting a flight-training run (`run`).

pub mod benchmark;
pub mod config;
pub mod curves;
pub mod flight_envs;
pub mod inverted_pendulum;
pub mod run;

pub use config::{TrainConfig, TrainConfigError};
pub use flight_envs::FlightEnvs;
pub use inverted_pendulum::InvertedPendulumEnvs;
