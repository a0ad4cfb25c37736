//! `flapper phase`: phase portraits of the wings and the paper's claims about them.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Result;
use flapper_analysis::phase::phase_portraits;
use flapper_eval::load_flight_policy;
use flapper_sim::RobotModel;

pub fn phase_command(robot: &RobotModel, policy_path: &Path, speed_mps: f64, out: &Path) -> Result<()> {
    if !(speed_mps.is_finite() && (2.0..=6.0).contains(&speed_mps)) {
        anyhow::bail!("--speed-mps must be in [2, 6] m/s, got {speed_mps}");
    }
    let (policy, task) = load_flight_policy(policy_path)?;
    crate::output_dir::prepare_output_dir(out)?;
    let (report, written) = phase_portraits(robot, Arc::new(policy), &task, speed_mps, out)?;
    println!(
        "phase portraits of {} (right wing; cruise and climb at {} m/s, climb {} m/s):",
        policy_path.display(),
        report.forward_speed_mps,
        report.climb_rate_mps
    );
    for (flight, orbits) in [("cruise", &report.cruise), ("climb", &report.climb)] {
        for (joint, o) in orbits.iter() {
            println!(
                "  {flight:<7} {joint:<12} mean {:>6.1} deg, amplitude {:>5.1} deg, velocity amplitude {:>5.0} deg/s, cycle spread {:>4.1}%",
                o.mean_deg, o.amplitude_deg, o.velocity_amplitude_degps, o.orbit_spread_percent
            );
        }
    }
    match (&report.turn_left, &report.turn_skipped_because) {
        (Some(orbits), _) => {
            for (joint, o) in orbits.iter() {
                println!(
                    "  turn L  {joint:<12} mean {:>6.1} deg, amplitude {:>5.1} deg, cycle spread {:>4.1}%",
                    o.mean_deg, o.amplitude_deg, o.orbit_spread_percent
                );
            }
        }
        (None, Some(why)) => println!("  left turn skipped: {why}"),
        (None, None) => {}
    }
    println!("the paper's claims:");
    for claim in &report.claims {
        println!(
            "  [{}] {} ({})",
            if claim.confirmed { "confirmed" } else { "NOT confirmed" },
            claim.claim,
            claim.ours
        );
    }
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// `flapper phase`'s options.
#[derive(clap::Args)]
pub struct PhaseArgs {
    /// Trained policy (a run's policy.safetensors or a checkpoint).
    #[arg(long, value_name = "FILE")]
    pub policy: PathBuf,
    /// Forward speed of the cruise and the climb (the paper: 3 m/s).
    #[arg(long, default_value_t = 3.0, allow_negative_numbers = true)]
    pub speed_mps: f64,
    /// Output folder (created if needed).
    #[arg(long, default_value = "run/phase")]
    pub out: PathBuf,
}

pub fn run(args: PhaseArgs, model: Option<&Path>) -> Result<()> {
    phase_command(&crate::robot::load(model)?, &args.policy, args.speed_mps, &args.out)
}
