//! `flapper export-policy`: a checkpoint's networks as a policy file, or the mean of several.

use std::path::{Path, PathBuf};

use anyhow::Result;

pub fn export_policy_command(checkpoints: &[PathBuf], out: &Path) -> Result<()> {
    let info = match checkpoints {
        [one] => flapper_ppo::checkpoint::export_policy(one, out)?,
        several => flapper_ppo::checkpoint::export_average_policy(several, out)?,
    };
    let averaged = if checkpoints.len() > 1 {
        format!("the mean of {} checkpoints, newest ", checkpoints.len())
    } else {
        String::new()
    };
    println!("wrote {} ({averaged}iteration {}, {} environment steps)", out.display(), info.iteration, info.env_steps);
    Ok(())
}

/// `flapper export-policy`'s options.
#[derive(clap::Args)]
pub struct ExportPolicyArgs {
    /// A checkpoint (runs/NAME/checkpoints/iter_NNNNNN.safetensors). Given several (oldest first, one run),
    /// the policy file holds the mean of their weights with the newest one's normalizer: the averaging a
    /// curriculum stage does with `average_checkpoints` (docs/training.md).
    #[arg(long, value_name = "FILE", num_args = 1.., required = true)]
    pub checkpoint: Vec<PathBuf>,
    /// The policy file to write (must not exist).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

pub fn run(args: ExportPolicyArgs) -> Result<()> {
    export_policy_command(&args.checkpoint, &args.out)
}
