//! `flapper export-policy`: a checkpoint's networks as a policy file.

use std::path::Path;

use anyhow::Result;

pub fn export_policy_command(checkpoint: &Path, out: &Path) -> Result<()> {
    let info = flapper_ppo::checkpoint::export_policy(checkpoint, out)?;
    println!("wrote {} (iteration {}, {} environment steps)", out.display(), info.iteration, info.env_steps);
    Ok(())
}
