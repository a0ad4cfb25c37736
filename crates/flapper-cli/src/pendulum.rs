//! `flapper pendulum`: the learner's known-answer check on the inverted pendulum.

use std::path::PathBuf;

use anyhow::Result;

use crate::flag_values::{count, seed};

/// `flapper pendulum`'s options.
#[derive(clap::Args)]
pub struct PendulumArgs {
    /// Seeds to train (one run each).
    #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5", value_parser = seed, allow_negative_numbers = true)]
    pub seeds: Vec<u64>,
    /// Give up after this many iterations (64 environments x 24 steps each).
    #[arg(long, default_value_t = 400, value_parser = count, allow_negative_numbers = true)]
    pub max_iterations: usize,
    /// Output folder (one run folder per seed; replaced if it exists).
    #[arg(long, default_value = "run/pendulum")]
    pub out: PathBuf,
}

pub fn run(args: PendulumArgs) -> Result<()> {
    crate::train::pendulum_command(&args.seeds, args.max_iterations, &args.out)
}
