//! `flapper report` and `flapper render`: the paper's figures regenerated, and one flight rendered.

use std::io::IsTerminal;
use std::path::Path;

use anyhow::Result;
use flapper_report::{ReportSettings, generate, render_flight, step_count};
use flapper_sim::RobotModel;
use indicatif::{ProgressBar, ProgressStyle};

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
    let bar = ProgressBar::new(step_count(settings) as u64);
    bar.set_style(ProgressStyle::with_template("{bar:30} {pos}/{len} steps  {elapsed_precise}  {msg}").expect("a valid template"));
    let interactive = std::io::stderr().is_terminal();
    if !interactive {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let outcome = generate(robot, settings, out, &|done: &str| {
        bar.set_message(done.to_owned());
        bar.inc(1);
        if !interactive {
            eprintln!("{}/{} ({:.0} s): {done}", bar.position(), bar.length().unwrap_or(0), bar.elapsed().as_secs_f64());
        }
    })?;
    bar.finish_and_clear();
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
