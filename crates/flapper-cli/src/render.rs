//! `flapper render`: one flight rendered offscreen, as a chase-camera video and overlaid snapshots.

use std::path::{Path, PathBuf};

use anyhow::Result;

use crate::flag_values::seed;

/// `flapper render`'s options.
#[derive(clap::Args)]
pub struct RenderArgs {
    /// Trained policy (a run's policy.safetensors or a checkpoint).
    #[arg(long, value_name = "FILE")]
    pub policy: PathBuf,
    /// A named reference (see `flapper reference --list`) or a CSV file of time_s,x_m,y_m,z_m.
    #[arg(long, default_value = "aerobatic")]
    pub reference: String,
    /// Seed of the randomized start.
    #[arg(long, default_value_t = 1, value_parser = seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// Output folder (created if needed).
    #[arg(long, default_value = "run/render")]
    pub out: PathBuf,
}

pub fn run(args: RenderArgs, model: Option<&Path>) -> Result<()> {
    crate::report::render_command(&crate::robot::load(model)?, &args.policy, &args.reference, args.seed, &args.out)
}
