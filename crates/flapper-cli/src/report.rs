//! `flapper report` and `flapper render`: the paper's figures regenerated, and one flight rendered.

use std::path::Path;

use anyhow::Result;
use flapper_report::{ReportSettings, generate, render_flight, step_count};
use flapper_sim::RobotModel;

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
