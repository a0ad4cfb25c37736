//! `flapper sysid`: identify the closed loop of a policy and print its transfer functions.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use anyhow::{Result, bail};
use flapper_analysis::linear_system::polynomial_text as polynomial;
use flapper_analysis::sysid::{AxisModel, SysidSettings, fly_records, identify, write_sysid_files};
use flapper_eval::load_flight_policy;
use flapper_sim::RobotModel;

use crate::flag_values::{count, seed};

fn roots(pairs: &[[f64; 2]]) -> String {
    pairs
        .iter()
        .map(|[re, im]| if *im == 0.0 { format!("{re:.3}") } else { format!("{re:.3}{im:+.3}i") })
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn sysid_command(robot: &RobotModel, policy_path: &Path, args: &SysidArgs) -> Result<()> {
    let amplitude_m = args.amplitude_m;
    if !(amplitude_m.is_finite() && amplitude_m > 0.0 && amplitude_m <= 1.0) {
        bail!("--amplitude-m must be in (0, 1] m, got {amplitude_m}");
    }
    if let Some(lead) = args.input_lead_s
        && !(0.0..=0.6).contains(&lead)
    {
        bail!("--input-lead-s must be in [0, 0.6] s (the policy's lookahead), got {lead}");
    }
    if !(1..=100).contains(&args.averaged_periods) {
        bail!("--averaged-periods must be between 1 and 100, got {}", args.averaged_periods);
    }
    let (policy, task) = load_flight_policy(policy_path)?;
    let settings = SysidSettings {
        seed: args.seed,
        amplitude_m,
        input_lead_s: args.input_lead_s,
        averaged_periods: args.averaged_periods,
        ..SysidSettings::default()
    };
    crate::output_dir::prepare_output_dir(&args.out)?;
    eprintln!(
        "flying {} identification and {} validation records of {:.0} s per axis, one axis perturbed at a time (cruise \
         {} m/s, target perturbed by {} m RMS, harmonics of {} Hz over {}-{} Hz, {} periods averaged)...",
        settings.identification_records,
        settings.validation_records,
        settings.record_s(),
        settings.cruise_speed_mps,
        amplitude_m,
        1.0 / settings.period_s,
        settings.band_hz[0],
        settings.band_hz[1],
        settings.averaged_periods
    );
    let records = fly_records(robot, Arc::new(policy), &task, &settings)?;
    let identified = identify(&records, &settings)?;
    let written = write_sysid_files(&args.out, &identified, &records)?;
    let report = &identified.report;
    println!(
        "closed loop of {}: desired position ahead -> flown position (deviations from a 3.8 m/s cruise)",
        policy_path.display()
    );
    let verdicts = |m: &AxisModel| {
        format!(
            "validation MSE {:.3e} m^2, fit {:.1}%; {}, {}",
            m.mse_validation,
            m.fit_percent,
            if m.bibo_stable { "BIBO stable" } else { "NOT BIBO stable" },
            if m.minimum_phase { "minimum phase" } else { "NOT minimum phase" }
        )
    };
    for (axis, m) in report.per_axis.each() {
        println!(
            "Y_{axis}(s) = ({}) / ({}), input lead {:.2} s",
            polynomial(&m.numerator),
            polynomial(&m.denominator),
            m.input_lead_s
        );
        println!("    poles {}; zeros {}; DC gain {:.3}", roots(&m.poles), roots(&m.zeros), m.dc_gain);
        println!("    {}", verdicts(m));
    }
    println!(
        "the paper's form, one denominator for the three axes ({}):",
        polynomial(&report.common_denominator.x.denominator)
    );
    for (axis, m) in report.common_denominator.each() {
        println!("  {axis}: poles {}; zeros {}; {}", roots(&m.poles), roots(&m.zeros), verdicts(m));
    }
    let [x, y, z] = &report.order_selection;
    println!(
        "the measured response's own validation fit (what a linear model of any order can be expected to reach): x \
         {:.1}%, y {:.1}%, z {:.1}%; best order by validation: x {}, y {}, z {} poles",
        x.nonparametric_fit_percent,
        y.nonparametric_fit_percent,
        z.nonparametric_fit_percent,
        x.best_poles,
        y.best_poles,
        z.best_poles
    );
    for path in written {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// `flapper sysid`'s options.
#[derive(clap::Args)]
pub struct SysidArgs {
    /// Trained policy (a run's policy.safetensors or a checkpoint).
    #[arg(long, value_name = "FILE")]
    pub policy: PathBuf,
    /// Seed of the perturbations' phases (identification and validation records differ).
    #[arg(long, default_value_t = 1, value_parser = seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// RMS of the target perturbation on each axis (m).
    #[arg(long, default_value_t = 0.15, allow_negative_numbers = true)]
    pub amplitude_m: f64,
    /// Take as input the desired position this far ahead (s, up to the 0.6 s the policy sees
    /// ahead; 0 is the paper's input, the current desired position). Default: per axis, the lead
    /// whose model best predicts the identification records.
    #[arg(long, allow_negative_numbers = true)]
    pub input_lead_s: Option<f64>,
    /// Periods of 20 s flown after the first and averaged into one: more average out more of the flight
    /// that does not follow the input, and take longer (a record lasts 20 s x (1 + this)).
    #[arg(long, default_value_t = SysidSettings::default().averaged_periods)]
    #[arg(value_parser = count, allow_negative_numbers = true)]
    pub averaged_periods: usize,
    /// Output folder (created if needed).
    #[arg(long, default_value = "run/sysid")]
    pub out: PathBuf,
}

pub fn run(args: SysidArgs, model: Option<&Path>) -> Result<()> {
    let robot = crate::robot::load(model)?;
    sysid_command(&robot, &args.policy, &args)
}
