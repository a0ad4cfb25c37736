//! `flapper frontier`: energy against tracking for several policies and the scripted gait (the
//! efficient-bird trade-off): a table, frontier.csv, energy_vs_tracking.svg and energy_vs_slow_flight.svg.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use flapper_analysis::frontier::file::read_frontier_csv;
use flapper_analysis::frontier::{
    FrontierPolicy, FrontierRow, FrontierSettings, LEVEL_3_REFERENCE, measure_frontier, step_count, table,
    write_frontier_files,
};
use flapper_sim::RobotModel;

use crate::flag_values::{count, seed};

/// `flapper frontier`'s options.
#[derive(clap::Args)]
pub struct FrontierArgs {
    /// A trained policy to measure; repeat the flag for several.
    #[arg(long = "policy", value_name = "FILE", required = true)]
    pub policies: Vec<PathBuf>,
    /// The name of each --policy in the table and the figure, in the same order (default: the
    /// policy's folder name, or a checkpoint's file name).
    #[arg(long = "label", value_name = "NAME")]
    pub labels: Vec<String>,
    /// Episodes per reference, each from its own randomized start (as `flapper eval`).
    #[arg(long, default_value_t = 100, value_parser = count, allow_negative_numbers = true)]
    pub episodes: usize,
    /// Seed of the randomized starts.
    #[arg(long, default_value_t = 11, value_parser = seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// Points measured elsewhere, in frontier.csv's columns with a `source` column naming the command
    /// (docs/energy-frontier.csv): drawn apart and copied into frontier.csv.
    #[arg(long, value_name = "FILE")]
    pub points: Option<PathBuf>,
    /// Output folder (created if needed): frontier.csv, energy_vs_tracking.svg, energy_vs_slow_flight.svg.
    #[arg(long, default_value = "run/frontier")]
    pub out: PathBuf,
}

/// Each `--policy` loaded with its `--label` (given in order; the default for the rest): more labels
/// than policies, or an empty one, is refused before any file is read.
pub fn load_labelled(policies: &[PathBuf], labels: &[String]) -> Result<Vec<FrontierPolicy>> {
    if labels.len() > policies.len() {
        bail!("--label given {} times for {} --policy: one name per policy, in order", labels.len(), policies.len());
    }
    if let Some(empty) = labels.iter().position(|l| l.trim().is_empty()) {
        bail!("--label number {} is empty", empty + 1);
    }
    let loaded = policies
        .iter()
        .enumerate()
        .map(|(k, path)| FrontierPolicy::load(labels.get(k).cloned().unwrap_or_else(|| default_label(path)), path))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(loaded)
}

/// A policy's name when no --label gives one: its folder's for a run's `policy.safetensors`, else
/// the file's name without its extension (a checkpoint).
fn default_label(path: &Path) -> String {
    let folder =
        path.parent().and_then(Path::file_name).filter(|_| path.file_name() == Some("policy.safetensors".as_ref()));
    folder.or_else(|| path.file_stem()).map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned())
}

pub fn frontier_command(robot: &RobotModel, args: &FrontierArgs) -> Result<()> {
    let FrontierArgs { policies, labels, episodes, seed, points: points_file, out } = args;
    if *episodes == 0 || *episodes > 100_000 {
        bail!("--episodes must be 1 to 100000, got {episodes}");
    }
    // Everything is read before anything is flown: a bad file stops the command at once.
    let loaded = load_labelled(policies, labels)?;
    let points = match points_file {
        Some(file) => read_frontier_csv(file)?,
        None => Vec::new(),
    };
    crate::output_dir::prepare_output_dir(out)?;
    let settings = FrontierSettings {
        episodes: *episodes,
        seed: *seed,
        level_reference: flapper_report::shipped_file(LEVEL_3_REFERENCE),
    };
    println!(
        "energy against tracking: {} {} and the scripted gait, {episodes} episodes per reference from randomized starts (seed {seed})",
        loaded.len(),
        if loaded.len() == 1 { "policy" } else { "policies" }
    );
    let began = std::time::Instant::now();
    let progress = crate::progress::Progress::new(step_count(loaded.len()), "flights");
    let frontier = measure_frontier(robot, &loaded, &settings, &|done: &str| progress.step_done(done))?;
    progress.finish();
    eprintln!("measured in {:.1} s", began.elapsed().as_secs_f64());
    for note in &frontier.notes {
        eprintln!("note: {note}");
    }
    print_table(frontier.rows());
    if let Some(file) = points_file {
        println!("and {} points measured elsewhere, from {}", points.len(), file.display());
    }
    for path in write_frontier_files(out, &frontier, &points)? {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The table, its first column left-aligned, the others right-aligned, each as wide as it needs.
fn print_table<'a>(rows: impl IntoIterator<Item = &'a FrontierRow>) {
    let (header, cells) = table(rows);
    let widths: Vec<usize> = (0..header.len())
        .map(|k| cells.iter().map(|row| row[k].len()).chain([header[k].len()]).max().unwrap_or(0))
        .collect();
    for row in std::iter::once(&header).chain(&cells) {
        let line: Vec<String> = row
            .iter()
            .enumerate()
            .map(
                |(k, cell)| {
                    if k == 0 { format!("{cell:<w$}", w = widths[k]) } else { format!("{cell:>w$}", w = widths[k]) }
                },
            )
            .collect();
        println!("{}", line.join("  "));
    }
}

pub fn run(args: FrontierArgs, model: Option<&Path>) -> Result<()> {
    frontier_command(&crate::robot::load(model)?, &args)
}
