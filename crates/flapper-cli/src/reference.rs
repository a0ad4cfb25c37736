//! `flapper reference`: a named or CSV reference resampled at the control period, as CSV and top and
//! side views.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};

pub fn reference_command(
    robot: &flapper_sim::RobotModel,
    reference: Option<&str>,
    list: bool,
    out: &Path,
) -> Result<()> {
    use flapper_task::reference::named::NAMED_REFERENCES;
    if list {
        for (name, what) in NAMED_REFERENCES {
            println!("{name:<20} {what}");
        }
        return Ok(());
    }
    let Some(reference) = reference else { bail!("give a reference name or CSV file (or --list)") };
    let dt_s = flapper_task::TaskConfig::default().control_period_s(robot.timestep_s());
    let loaded = flapper_task::reference::resolve(reference, dt_s, 0)?;
    crate::output_dir::prepare_output_dir(out)?;
    let csv_path = out.join("reference.csv");
    let text = flapper_task::reference::csv_file::reference_csv_text(loaded.points(), dt_s);
    flapper_plot::write_atomically(&csv_path, text.as_bytes())
        .with_context(|| format!("cannot write '{}'", csv_path.display()))?;
    let plot = out.join("reference.svg");
    flapper_eval::write_path_views(loaded.points(), loaded.name(), &plot)?;
    let speeds: Vec<f64> = (0..loaded.len() - 1).map(|k| loaded.speed(k)).collect();
    let (z_min, z_max) = loaded.points().iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(p.z), hi.max(p.z)));
    println!(
        "{}: {:.2} s, {} points at 50 Hz, speed {:.2}-{:.2} m/s, altitude {:.2}-{:.2} m",
        loaded.name(),
        loaded.duration_s(),
        loaded.len(),
        speeds.iter().copied().fold(f64::MAX, f64::min),
        speeds.iter().copied().fold(f64::MIN, f64::max),
        z_min,
        z_max
    );
    println!("wrote {}", csv_path.display());
    println!("wrote {}", plot.display());
    Ok(())
}

/// `flapper reference`'s options.
#[derive(clap::Args)]
pub struct ReferenceArgs {
    /// A named reference (see --list) or a CSV file of time_s,x_m,y_m,z_m.
    #[arg(required_unless_present = "list")]
    pub reference: Option<String>,
    /// List the named references and exit.
    #[arg(long)]
    pub list: bool,
    /// Output directory (created if needed).
    #[arg(long, default_value = "run/reference")]
    pub out: PathBuf,
}

pub fn run(args: ReferenceArgs, model: Option<&Path>) -> Result<()> {
    reference_command(&crate::robot::load(model)?, args.reference.as_deref(), args.list, &args.out)
}
