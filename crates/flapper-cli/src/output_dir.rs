//! The folder a command writes into (`--out`): flapper's own, or refused, so no run overwrites a
//! file it did not write.

use std::path::Path;

use anyhow::{Context, Result, bail};

/// Marks a folder as flapper's output: a later command may replace what is in it.
pub const OUTPUT_MARKER: &str = ".flapper-output";

/// Creates `out`, or takes it when it is empty or was made by flapper (it holds [`OUTPUT_MARKER`]);
/// a folder holding other files is refused before anything is written.
pub fn prepare_output_dir(out: &Path) -> Result<()> {
    if out.exists() && !out.is_dir() {
        bail!("--out '{}' is a file, not a folder", out.display());
    }
    let has_files = out.is_dir()
        && std::fs::read_dir(out).with_context(|| format!("cannot read '{}'", out.display()))?.next().is_some();
    if has_files && !out.join(OUTPUT_MARKER).exists() {
        bail!(
            "--out '{}' holds files flapper did not write (no {OUTPUT_MARKER} in it), which this command could overwrite; give a new or empty folder",
            out.display()
        );
    }
    std::fs::create_dir_all(out).with_context(|| format!("cannot create output directory '{}'", out.display()))?;
    let marker = out.join(OUTPUT_MARKER);
    if !marker.exists() {
        flapper_plot::write_atomically(
            &marker,
            b"written by flapper: files here are replaced by the next command writing here\n",
        )
        .with_context(|| format!("cannot write '{}'", marker.display()))?;
    }
    Ok(())
}
