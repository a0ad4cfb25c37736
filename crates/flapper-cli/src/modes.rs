//! `flapper modes`: flapping and power per segment of the longitudinal reference: does the policy glide?

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::Result;
use flapper_analysis::modes::{GLIDE_MAX_FLAP_RANGE_DEG, GLIDE_WINDOW_S, GLIDING_SEGMENT_FRACTION, flight_modes};
use flapper_eval::load_flight_policy;
use flapper_sim::RobotModel;

pub fn modes_command(robot: &RobotModel, policy_path: &Path, out: &Path) -> Result<()> {
    let (policy, task) = load_flight_policy(policy_path)?;
    crate::output_dir::prepare_output_dir(out)?;
    let (report, written) = flight_modes(robot, Arc::new(policy), &task, out)?;
    println!("flight modes of {} on the longitudinal reference (exact start):", policy_path.display());
    println!(
        "{:<8} {:>9} {:>16} {:>14} {:>12} {:>18} {:>14} {:>14}  glides",
        "segment",
        "time (s)",
        "flap ampl. (deg)",
        "flap fund. (Hz)",
        "energy (%)",
        "power (W) net/abs",
        "energy (J/m)",
        "glide fraction"
    );
    for s in &report.segments {
        println!(
            "{:<8} {:>4.0}-{:<4.0} {:>16.1} {:>14.2} {:>12.0} {:>11.1} / {:<5.1} {:>14.2} {:>14.2}  {}",
            s.segment,
            s.start_s,
            s.end_s,
            s.flap_amplitude_deg,
            s.flap_fundamental_hz,
            100.0 * s.flap_energy_fraction,
            s.mean_power_w,
            s.mean_absolute_power_w,
            s.energy_per_metre_j,
            s.glide_fraction,
            if s.glides { "yes" } else { "no" }
        );
    }
    println!(
        "gliding: flap range below {GLIDE_MAX_FLAP_RANGE_DEG} deg peak to peak over the {GLIDE_WINDOW_S} s around each moment; a segment glides from a glide fraction of {GLIDING_SEGMENT_FRACTION}"
    );
    println!("does it glide? {}", report.verdict);
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// `flapper modes`'s options.
#[derive(clap::Args)]
pub struct ModesArgs {
    /// Trained policy (a run's policy.safetensors or a checkpoint).
    #[arg(long, value_name = "FILE")]
    pub policy: PathBuf,
    /// Output folder (created if needed).
    #[arg(long, default_value = "run/modes")]
    pub out: PathBuf,
}

pub fn run(args: ModesArgs, model: Option<&Path>) -> Result<()> {
    modes_command(&crate::robot::load(model)?, &args.policy, &args.out)
}
