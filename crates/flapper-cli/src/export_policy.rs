//! `flapper export-policy`: a checkpoint's networks as a policy file.

use std::path::{Path, PathBuf};

use anyhow::Result;

pub fn export_policy_command(checkpoint: &Path, out: &Path) -> Result<()> {
    let info = flapper_ppo::checkpoint::export_policy(checkpoint, out)?;
    println!("wrote {} (iteration {}, {} environment steps)", out.display(), info.iteration, info.env_steps);
    Ok(())
}

/// `flapper export-policy`'s options.
#[derive(clap::Args)]
pub struct ExportPolicyArgs {
    /// A checkpoint (runs/NAME/checkpoints/iter_NNNNNN.safetensors).
    #[arg(long, value_name = "FILE")]
    pub checkpoint: PathBuf,
    /// The policy file to write (must not exist).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

pub fn run(args: ExportPolicyArgs) -> Result<()> {
    export_policy_command(&args.checkpoint, &args.out)
}
