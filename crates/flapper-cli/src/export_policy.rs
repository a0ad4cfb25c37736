//! `flapper export-policy`: a checkpoint's networks as a policy file (or the mean of several), or a
//! policy as ONNX or as a C99 source file for a robot (docs/deploy.md).

use std::fmt;
use std::path::{Path, PathBuf};
use std::process::Command;

use anyhow::{Context, Result, bail};
use flapper_deploy::c_compiler::{CCompiler, time_policy};
use flapper_deploy::{DeployablePolicy, refuse_existing};
use flapper_ppo::checkpoint::CheckpointKind;

/// What `--format` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    /// A policy file (safetensors and its JSON): flies, evaluates, starts a new run.
    Safetensors,
    /// ONNX: the normalizer and the actor as one graph, the facts in its metadata.
    Onnx,
    /// One C99 header and source file.
    C,
}

impl ExportFormat {
    const ALL: [(&'static str, ExportFormat); 3] =
        [("safetensors", Self::Safetensors), ("onnx", Self::Onnx), ("c", Self::C)];
}

impl std::str::FromStr for ExportFormat {
    type Err = anyhow::Error;

    fn from_str(text: &str) -> Result<Self> {
        match Self::ALL.iter().find(|(name, _)| *name == text) {
            Some((_, format)) => Ok(*format),
            None => {
                let names: Vec<&str> = Self::ALL.iter().map(|(name, _)| *name).collect();
                bail!("unknown --format '{text}' (the formats are {})", names.join(", "))
            }
        }
    }
}

impl fmt::Display for ExportFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let name = Self::ALL.iter().find(|(_, format)| format == self).map_or("?", |(name, _)| name);
        f.write_str(name)
    }
}

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

/// "policies/final/policy.safetensors (a policy file, iteration 800, 4915200 environment steps)".
fn describe_source(path: &Path, policy: &DeployablePolicy) -> String {
    let facts = &policy.facts;
    let kind = match facts.source_kind {
        CheckpointKind::Policy => "a policy file",
        CheckpointKind::Checkpoint => "a checkpoint of a training run",
    };
    format!(
        "{} ({kind}, iteration {}, {} environment steps)",
        path.display(),
        facts.training_iteration,
        facts.training_env_steps
    )
}

fn print_size(policy: &DeployablePolicy) {
    println!(
        "{} multiply-adds per action ({} normalized inputs, layers {:?}), {} bytes of float32 numbers",
        policy.facts.multiply_adds,
        policy.arrays.observation_size(),
        policy.arrays.layers.iter().map(|l| l.fan_out).collect::<Vec<_>>(),
        policy.facts.weight_bytes
    );
}

/// The Python that writes ONNX: `$FLAPPER_PYTHON`, else the `.venv` that `make python` builds, here or
/// in the repository that holds this binary (target/release/flapper).
fn python_for_onnx() -> Result<PathBuf> {
    if let Some(python) = std::env::var_os("FLAPPER_PYTHON").filter(|p| !p.is_empty()) {
        return Ok(PathBuf::from(python));
    }
    let beside_binary =
        std::env::current_exe().ok().and_then(|exe| exe.parent()?.parent()?.parent().map(Path::to_path_buf));
    let candidates =
        [Some(PathBuf::from(".")), beside_binary].into_iter().flatten().map(|root| root.join(".venv/bin/python"));
    for python in candidates {
        if python.exists() {
            return Ok(python);
        }
    }
    bail!(
        "--format onnx is written by flapper's Python package (with the onnx library) and no .venv/bin/python was found: run `make python` in the repository (or set FLAPPER_PYTHON to a Python that has `pip install ./crates/flapper-py[test]`)"
    )
}

fn write_onnx(policy_path: &Path, out: &Path, model: Option<&Path>) -> Result<()> {
    let python = python_for_onnx()?;
    let mut command = Command::new(&python);
    command.args(["-m", "flapper.onnx_export", "--policy"]).arg(policy_path).arg("--out").arg(out);
    if let Some(model) = model {
        command.arg("--model").arg(model);
    }
    let done = command.output().with_context(|| format!("cannot run '{}' to write ONNX", python.display()))?;
    if !done.status.success() {
        let stderr = String::from_utf8_lossy(&done.stderr);
        let last = stderr.lines().rev().find(|l| !l.trim().is_empty()).unwrap_or("no message").trim().to_owned();
        bail!(
            "'{}' could not write ONNX ({last}): run `make python` to install flapper with onnx into .venv",
            python.display()
        );
    }
    Ok(())
}

fn export_for_robot(format: ExportFormat, policy_path: &Path, out: &Path, model: Option<&Path>) -> Result<()> {
    match format {
        ExportFormat::C => {
            let (source, header) = flapper_deploy::c_file_pair(out)?;
            refuse_existing(&source)?;
            refuse_existing(&header)?;
        }
        _ => refuse_existing(out)?,
    }
    let robot = crate::robot::load(model)?;
    let policy = DeployablePolicy::load(policy_path, &robot)?;
    let source = describe_source(policy_path, &policy);
    match format {
        ExportFormat::Onnx => {
            write_onnx(policy_path, out, model)?;
            println!("wrote {} (ONNX, opset 17: the normalizer and the actor) from {source}", out.display());
            print_size(&policy);
        }
        ExportFormat::C => {
            let header = flapper_deploy::write_c_source(&policy, out)?;
            println!("wrote {} and {} (C99) from {source}", out.display(), header.display());
            print_size(&policy);
            match CCompiler::find() {
                Some(compiler) => {
                    let latency = time_policy(&compiler, out, &header, &std::env::temp_dir())?;
                    println!(
                        "one call of the compiled C: {:.1} us on this CPU ({}, {})",
                        latency.per_call_us, latency.compiler, latency.flags
                    );
                }
                None => println!("no C compiler found (cc, or $CC): latency not measured"),
            }
        }
        ExportFormat::Safetensors => unreachable!("a policy file is written by export_policy_command"),
    }
    Ok(())
}

/// `flapper export-policy`'s options.
#[derive(clap::Args)]
pub struct ExportPolicyArgs {
    /// A policy file or a checkpoint (runs/NAME/checkpoints/iter_NNNNNN.safetensors; a running
    /// training's checkpoint is fine). Given several (oldest first, one run; --format safetensors only),
    /// the policy file holds the mean of their weights with the newest one's normalizer: the averaging a
    /// curriculum stage does with `average_checkpoints` (docs/training.md).
    #[arg(long, visible_alias = "checkpoint", value_name = "FILE", num_args = 1.., required = true)]
    pub policy: Vec<PathBuf>,
    /// What to write: safetensors (a policy file), onnx (the normalizer and actor as an ONNX graph,
    /// written through the Python package: `make python` first), or c (NAME.c and NAME.h, C99); onnx
    /// and c: docs/deploy.md.
    #[arg(long, default_value = "safetensors", value_name = "FORMAT")]
    pub format: String,
    /// The file to write (must not exist; for --format c, NAME.c, with NAME.h beside it).
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

pub fn run(args: ExportPolicyArgs, model: Option<&Path>) -> Result<()> {
    let format: ExportFormat = args.format.parse()?;
    match (format, args.policy.as_slice()) {
        (ExportFormat::Safetensors, files) => export_policy_command(files, &args.out),
        (_, [one]) => export_for_robot(format, one, &args.out, model),
        (_, several) => bail!(
            "--format {format} exports one policy, got {} files: average them into a policy file first (--format safetensors)",
            several.len()
        ),
    }
}
