//! `flapper report` and `flapper render`: the paper's figures regenerated, and one flight rendered.

use std::path::{Path, PathBuf};

use anyhow::Result;
use flapper_report::{ReportSettings, generate, render_flight, step_count};
use flapper_sim::RobotModel;

use crate::flag_values::{count, seed};

pub fn report_command(robot: &RobotModel, settings: &ReportSettings, out: &Path) -> Result<()> {
    crate::output_dir::prepare_output_dir(out)?;
    println!(
        "report of {} into {}: {} starts per reference, {} per robustness setting, seed {}",
        settings.policy.display(),
        out.display(),
        settings.episodes,
        settings.robustness_episodes,
        settings.seed
    );
    let progress = crate::progress::Progress::new(step_count(settings), "steps");
    let outcome = generate(robot, settings, out, &|done: &str| progress.step_done(done))?;
    progress.finish();
    for note in &outcome.notes {
        eprintln!("note: {note}");
    }
    println!("took {:.0} s", outcome.wall_time_s);
    println!("wrote {}", outcome.index_html.display());
    println!("wrote {}", outcome.report_md.display());
    Ok(())
}

pub fn render_command(robot: &RobotModel, policy: &Path, reference: &str, seed: u64, out: &Path) -> Result<()> {
    crate::output_dir::prepare_output_dir(out)?;
    let (written, note) = render_flight(robot, policy, reference, seed, out)?;
    if let Some(note) = note {
        eprintln!("note: {note}");
    }
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// `flapper report`'s options.
#[derive(clap::Args)]
pub struct ReportArgs {
    /// The controller the report shows (default: the final shipped controller).
    #[arg(long, value_name = "FILE", default_value = flapper_report::FINAL_POLICY)]
    pub policy: PathBuf,
    /// Randomized starts per named reference.
    #[arg(long, default_value_t = 100, value_parser = count, allow_negative_numbers = true)]
    pub episodes: usize,
    /// Episodes per setting of the robustness sweeps (fluid coefficients, winds, Table III).
    #[arg(long, default_value_t = 50, value_parser = count, allow_negative_numbers = true)]
    pub robustness_episodes: usize,
    /// Seed of the randomized starts and the drawn dynamics.
    #[arg(long, default_value_t = 1, value_parser = seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// Skip the rendered snapshots and the video (everything else is written).
    #[arg(long)]
    pub no_pictures: bool,
    /// Output folder (created if needed).
    #[arg(long, default_value = "run/report")]
    pub out: PathBuf,
}

pub fn run(args: ReportArgs, model: Option<&Path>) -> Result<()> {
    let settings = ReportSettings {
        policy: if args.policy == Path::new(flapper_report::FINAL_POLICY) {
            flapper_report::shipped_file(flapper_report::FINAL_POLICY)
        } else {
            args.policy
        },
        episodes: args.episodes,
        robustness_episodes: args.robustness_episodes,
        seed: args.seed,
        pictures: !args.no_pictures,
        ..Default::default()
    };
    report_command(&crate::robot::load(model)?, &settings, &args.out)
}
