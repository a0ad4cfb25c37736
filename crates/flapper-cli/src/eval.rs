//! `flapper eval`: fly a policy and the scripted baseline on one reference, print the table side by
//! side, write CSV and plots per controller and a summary CSV.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Context, Result, bail};
use flapper_analysis::modes::{LONGITUDINAL, SETTLE_S, SegmentOverFlights, segments_over_flights, write_segments_csv};
use flapper_eval::ScriptedGaitConfig;
use flapper_eval::load_flight_policy;
use flapper_eval::tracking::{TrackingController, evaluate_tracking};
use flapper_eval::tracking_report::{
    TrackingSummary, write_observations_csv, write_start_json, write_steps_csv, write_summary_csv, write_tracking_plots,
};
use flapper_sim::RobotModel;
use flapper_task::TaskConfig;
use flapper_task::reference::NAMED_START_M;

use crate::flag_values::{count, seed};

/// What `flapper eval` flies, checked and borrowed from [`EvalArgs`].
pub struct EvalRequest<'a> {
    pub policy: Option<&'a Path>,
    pub reference: &'a str,
    pub episodes: usize,
    pub seed: u64,
    pub out: &'a Path,
    /// Fly the scripted gait too.
    pub baseline: bool,
    /// Write episode 0's observations and actions per controller.
    pub observations: bool,
}

pub fn eval_command(robot: &RobotModel, args: EvalRequest) -> Result<()> {
    let EvalRequest { policy: policy_path, reference, episodes, seed, out, baseline, observations } = args;
    if episodes == 0 || episodes > 100_000 {
        bail!("--episodes must be 1 to 100000, got {episodes}");
    }
    if policy_path.is_none() && !baseline {
        bail!("nothing to fly: give --policy, or drop --no-baseline");
    }
    let mut controllers: Vec<(&str, TrackingController, TaskConfig)> = Vec::new();
    if let Some(path) = policy_path {
        let (policy, task) = load_flight_policy(path)?;
        controllers.push(("policy", TrackingController::Policy(Arc::new(policy)), task));
    }
    if baseline {
        controllers.push((
            "scripted",
            TrackingController::Scripted(ScriptedGaitConfig::default()),
            TaskConfig::default(),
        ));
    }
    let lookahead = controllers[0].2.observation.lookahead_steps;
    // Every controller's task steps at the same rate: the control substeps are the paper's for both.
    let dt_s = controllers[0].2.control_period_s(robot.timestep_s());
    let reference = Arc::new(flapper_task::reference::resolve(reference, dt_s, lookahead)?);
    // The named reference itself, not a file that happens to share its name.
    let per_segment = reference.name() == LONGITUDINAL
        && flapper_task::reference::named::named(LONGITUDINAL, NAMED_START_M, dt_s, lookahead as f64 * dt_s).as_ref()
            == Some(reference.as_ref());
    if let Some(warning) = flapper_eval::tracking::speed_warning(&reference) {
        eprintln!("warning: {warning}");
    }
    crate::output_dir::prepare_output_dir(out)?;
    println!(
        "{}: {:.1} s, {} episodes from randomized starts (seed {seed})",
        reference.name(),
        reference.duration_s(),
        episodes
    );
    let mut summaries = Vec::new();
    let mut segments = Vec::new();
    for (name, controller, task) in &controllers {
        let began = std::time::Instant::now();
        let results = evaluate_tracking(robot, controller, task, reference.clone(), episodes, seed)?;
        let period = task.control_period_s(robot.timestep_s());
        let summary =
            TrackingSummary::of(&results, period, flapper_task::reference::named::manoeuvre_window_s(reference.name()));
        let dir = out.join(name);
        std::fs::create_dir_all(&dir).with_context(|| format!("cannot create output directory '{}'", dir.display()))?;
        write_steps_csv(&results, &dir.join("steps.csv"))?;
        if per_segment {
            let figures = segments_over_flights(&results, period);
            write_segments_csv(&dir.join("segments.csv"), &figures)?;
            segments.push((*name, figures));
        }
        if observations {
            let (_, record) =
                flapper_eval::tracking::record_episode(robot, controller, task, reference.clone(), seed, 0)?;
            let names = flapper_task::observation::ObservationLayout::of(&task.observation).names();
            write_observations_csv(&record, &names, &dir.join("observations.csv"))?;
            write_start_json(&record, &dir.join("start.json"))?;
        }
        let plots = write_tracking_plots(&results, &format!("{name} on {}", reference.name()), &dir, 3)?;
        eprintln!(
            "  {name}: {} episodes in {:.1} s, wrote {} and {} plots",
            episodes,
            began.elapsed().as_secs_f64(),
            dir.join("steps.csv").display(),
            plots.len()
        );
        summaries.push((*name, summary));
    }
    let tables: Vec<Vec<(String, String)>> = summaries.iter().map(|(_, s)| s.rows()).collect();
    print!("{:<36}", "");
    for (name, _) in &summaries {
        print!("{name:>26}");
    }
    println!();
    for (k, (label, _)) in tables[0].iter().enumerate() {
        print!("{label:<36}");
        for table in &tables {
            print!("{:>26}", table[k].1);
        }
        println!();
    }
    if !segments.is_empty() {
        print_segments(&segments);
    }
    let summary_path = out.join("summary.csv");
    write_summary_csv(&summaries, &summary_path)?;
    println!("wrote {} and per-controller folders in {}", summary_path.display(), out.display());
    Ok(())
}

/// Per segment of the longitudinal reference and per controller, the figures over the flights from
/// randomized starts (each controller's `segments.csv`).
fn print_segments(segments: &[(&str, Vec<SegmentOverFlights>)]) {
    println!(
        "per segment of the longitudinal reference (mean over the flights that flew it to its end; the launch's first {SETTLE_S:.0} s left out):"
    );
    println!(
        "{:<10} {:<8} {:>9} {:>10} {:>14} {:>10} {:>15}",
        "", "segment", "time (s)", "flights", "|power| (W)", "error (m)", "energy (J/m)"
    );
    for (name, rows) in segments {
        for row in rows {
            println!(
                "{:<10} {:<8} {:>4.0}-{:<4.0} {:>5}/{:<4} {:>14.1} {:>10.2} {:>15.2}   glide fraction {:.2}",
                name,
                row.segment,
                row.start_s,
                row.end_s,
                row.flights,
                row.episodes,
                row.mean_absolute_power_w,
                row.mean_error_m,
                row.energy_per_metre_j,
                row.glide_fraction
            );
        }
    }
}

/// `flapper eval`'s options.
#[derive(clap::Args)]
pub struct EvalArgs {
    /// Trained policy (a run's policy.safetensors or a checkpoint); required unless --baseline-only.
    #[arg(long, value_name = "FILE")]
    pub policy: Option<PathBuf>,
    /// A named reference (see `flapper reference --list`) or a CSV file of time_s,x_m,y_m,z_m.
    #[arg(long, default_value = "longitudinal")]
    pub reference: String,
    /// Episodes, each from its own randomized start.
    #[arg(long, default_value_t = 100, value_parser = count, allow_negative_numbers = true)]
    pub episodes: usize,
    /// Seed of the randomized starts.
    #[arg(long, default_value_t = 1, value_parser = seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// Output folder (created if needed): policy/ and scripted/ subfolders and summary.csv.
    #[arg(long, default_value = "run/eval")]
    pub out: PathBuf,
    /// Do not fly the scripted baseline.
    #[arg(long)]
    pub no_baseline: bool,
    /// Fly only the scripted baseline (no policy).
    #[arg(long, conflicts_with_all = ["policy", "no_baseline"])]
    pub baseline_only: bool,
    /// Also write what each controller saw and did in episode 0 (observations and actions, one row
    /// per control step) as PILOT/observations.csv, and its initial state as PILOT/start.json: for
    /// checking another implementation (docs/deploy.md).
    #[arg(long)]
    pub observations: bool,
}

pub fn run(args: EvalArgs, model: Option<&Path>) -> Result<()> {
    if args.policy.is_none() && !args.baseline_only {
        bail!(
            "give --policy FILE (the final controller: {}), or --baseline-only to fly the scripted gait alone",
            flapper_report::FINAL_POLICY
        );
    }
    let request = EvalRequest {
        policy: args.policy.as_deref(),
        reference: &args.reference,
        episodes: args.episodes,
        seed: args.seed,
        out: &args.out,
        baseline: !args.no_baseline,
        observations: args.observations,
    };
    eval_command(&crate::robot::load(model)?, request)
}
