//! `flapper robustness`: the paper's robustness sweeps (Fig. 8-9) on one reference, with a progress
//! bar; tables on stdout, CSV, JSON and plots in the output folder.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Result, bail};
use flapper_analysis::robustness::{MAX_RANGE, PAPER_RANGES, RobustnessSettings, Sweep, robustness, write_robustness};
use flapper_eval::load_flight_policy;
use flapper_eval::tracking::TrackingController;
use flapper_sim::RobotModel;

use crate::flag_values::{count, seed};

/// What `flapper robustness` runs, borrowed from [`RobustnessArgs`].
pub struct RobustnessRequest<'a> {
    pub policy: &'a Path,
    pub reference: &'a str,
    pub episodes: usize,
    pub seed: u64,
    pub sweeps: &'a [String],
    /// The fluid sweep's ranges; the paper's when not given.
    pub ranges: Option<&'a [f64]>,
    pub out: &'a Path,
}

/// The sweeps named in --sweeps, each once, in the order given.
fn parse_sweeps(names: &[String]) -> Result<Vec<Sweep>> {
    let mut sweeps = Vec::new();
    for name in names {
        let Some(sweep) = Sweep::parse(name) else {
            let known: Vec<&str> = Sweep::ALL.iter().map(|s| s.name()).collect();
            bail!("unknown sweep '{name}' in --sweeps (known: {})", known.join(", "));
        };
        if !sweeps.contains(&sweep) {
            sweeps.push(sweep);
        }
    }
    Ok(sweeps)
}

fn check_ranges(ranges: &[f64]) -> Result<()> {
    if let Some(bad) = ranges.iter().find(|r| !(r.is_finite() && (0.0..=MAX_RANGE).contains(*r))) {
        bail!(
            "--ranges: each range must be in [0, {MAX_RANGE}] (coefficients drawn from [1 - r, 1 + r] x nominal), got {bad}"
        );
    }
    if ranges.is_empty() || ranges.len() > 100 {
        bail!("--ranges: give 1 to 100 ranges, got {}", ranges.len());
    }
    Ok(())
}

pub fn robustness_command(robot: &RobotModel, args: RobustnessRequest) -> Result<()> {
    if args.episodes == 0 || args.episodes > 100_000 {
        bail!("--episodes must be 1 to 100000, got {}", args.episodes);
    }
    let sweeps = parse_sweeps(args.sweeps)?;
    let ranges = args.ranges.unwrap_or(&PAPER_RANGES);
    check_ranges(ranges)?;
    let (policy, task) = load_flight_policy(args.policy)?;
    let reference = Arc::new(flapper_task::reference::resolve(
        args.reference,
        task.control_period_s(robot.timestep_s()),
        task.observation.lookahead_steps,
    )?);
    if let Some(warning) = flapper_eval::tracking::speed_warning(&reference) {
        eprintln!("warning: {warning}");
    }
    crate::output_dir::prepare_output_dir(args.out)?;
    let settings = RobustnessSettings {
        sweeps,
        episodes: args.episodes,
        seed: args.seed,
        ranges: ranges.to_vec(),
        winds: flapper_analysis::robustness::default_winds(),
    };
    println!(
        "robustness of {} on {} ({:.1} s): {} settings of {} episodes (seed {}), sweeps {}",
        args.policy.display(),
        reference.name(),
        reference.duration_s(),
        settings.settings_count(),
        args.episodes,
        args.seed,
        settings.sweeps.iter().map(|s| s.name()).collect::<Vec<_>>().join(", ")
    );
    let progress = crate::progress::Progress::new(settings.settings_count(), "settings");
    let controller = TrackingController::Policy(Arc::new(policy));
    let (report, wind_paths) =
        robustness(robot, &controller, &task, reference.clone(), &settings, &|done: &str| progress.step_done(done))?;
    progress.finish();

    if !report.fluid.is_empty() {
        println!("fluid coefficients, success rate (%) by range r (x[1 - r, 1 + r], the others nominal, no wind):");
        print!("{:<10}", "");
        for r in &settings.ranges {
            print!("{:>8}", format!("r={r}"));
        }
        println!();
        for series in flapper_analysis::robustness::FluidSeries::ALL {
            print!("{:<10}", series.name());
            for f in report.fluid.iter().filter(|f| f.coefficient == series.name()) {
                print!("{:>8.0}", 100.0 * f.tally.success_rate);
            }
            println!();
        }
        if let Some(name) = &report.most_sensitive_coefficient {
            println!("most sensitive single coefficient (lowest success at the widest range): {name}");
        }
    }
    if !report.wind.is_empty() {
        println!(
            "constant winds (world frame; the reference starts along +x), and the airspeeds the reference then asks for:"
        );
        for w in &report.wind {
            let envelope = match w.inside_envelope {
                Some(true) => "  inside the level envelope",
                Some(false) => "  OUTSIDE the level envelope",
                None => "",
            };
            println!(
                "  {:<26} ({:>4.1}, {:>4.1}, {:>4.1}) m/s  {:>3}/{}  RMS {:.3} m  needs {:.1}-{:.1} m/s{envelope}",
                w.name,
                w.wind_mps[0],
                w.wind_mps[1],
                w.wind_mps[2],
                w.tally.successes,
                w.tally.episodes,
                w.tally.mean_rms_error_m,
                w.needed_airspeed.slowest_mps,
                w.needed_airspeed.fastest_mps
            );
        }
        if report.envelope.is_none() {
            println!("  (add the envelope sweep, --sweeps ...,envelope, to see which needs the robot can fly)");
        }
    }
    if let Some(t) = &report.table_iii {
        println!(
            "everything in Table III randomized at once: {}/{} ({:.0}%), RMS {:.3} m",
            t.successes,
            t.episodes,
            100.0 * t.success_rate,
            t.mean_rms_error_m
        );
    }
    if let (Some(inside), Some(envelope)) = (&report.table_iii_inside_envelope, &report.envelope) {
        println!(
            "  of its episodes whose drawn wind keeps the reference's airspeeds inside the level envelope ({}-{} m/s): {}/{} ({:.0}%)",
            envelope.slowest_sustained_mps.unwrap_or(f64::NAN),
            envelope.fastest_sustained_mps.unwrap_or(f64::NAN),
            inside.successes,
            inside.episodes,
            100.0 * inside.success_rate
        );
    }
    if let Some(envelope) = &report.envelope {
        let speeds: Vec<String> =
            envelope.speeds.iter().map(|(v, t)| format!("{v}: {}/{}", t.successes, t.episodes)).collect();
        println!("level flight, 15 s at each airspeed (m/s), completed: {}", speeds.join(", "));
        match (envelope.slowest_sustained_mps, envelope.fastest_sustained_mps) {
            (Some(lo), Some(hi)) => println!("sustained level airspeeds (>= 90% completed): {lo} to {hi} m/s"),
            _ => println!("no level airspeed was sustained (>= 90% completed)"),
        }
    }
    println!("took {:.1} s", report.wall_time_s);
    for path in write_robustness(&report, &wind_paths, &reference, args.out)? {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// `flapper robustness`'s options.
#[derive(clap::Args)]
pub struct RobustnessArgs {
    /// Trained policy (a run's policy.safetensors or a checkpoint).
    #[arg(long, value_name = "FILE")]
    pub policy: PathBuf,
    /// A named reference (see `flapper reference --list`) or a CSV file of time_s,x_m,y_m,z_m.
    #[arg(long, default_value = "longitudinal")]
    pub reference: String,
    /// Episodes per setting, each from its own randomized start.
    #[arg(long, default_value_t = 100, value_parser = count, allow_negative_numbers = true)]
    pub episodes: usize,
    /// Seed of the starts and of the drawn dynamics.
    #[arg(long, default_value_t = 1, value_parser = seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// Which sweeps to run (comma-separated): fluid, wind, table3, envelope.
    #[arg(long, value_delimiter = ',', default_value = "fluid,wind,table3,envelope")]
    pub sweeps: Vec<String>,
    /// Randomization ranges r of the fluid sweep (comma-separated; coefficients x[1 - r, 1 + r]).
    /// Default: the paper's 0, 0.1, 0.2, 0.3, 0.4, 0.5.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub ranges: Option<Vec<f64>>,
    /// Output folder (created if needed).
    #[arg(long, default_value = "run/robustness")]
    pub out: PathBuf,
}

pub fn run(args: RobustnessArgs, model: Option<&Path>) -> Result<()> {
    let request = RobustnessRequest {
        policy: &args.policy,
        reference: &args.reference,
        episodes: args.episodes,
        seed: args.seed,
        sweeps: &args.sweeps,
        ranges: args.ranges.as_deref(),
        out: &args.out,
    };
    robustness_command(&crate::robot::load(model)?, request)
}
