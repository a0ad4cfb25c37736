//! `flapper power-curve`: what straight and level flight costs at each airspeed. The scripted gait's
//! family is flown level, the cheapest gait per airspeed drawn as the curve, and policies fly level
//! paths beside it: a table, gaits.csv, power_curve.csv, policies_level.csv and power_curve.svg.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use flapper_analysis::power_curve::{
    GAIT_FLIGHT_S, GaitFamily, LEVEL_TOLERANCE_M, PowerCurve, PowerCurveSettings, SETTLED_AFTER_S, SPEED_BIN_MPS,
    measure_power_curve, step_count, write_power_curve,
};
use flapper_sim::RobotModel;

use crate::flag_values::{count, seed};
use crate::frontier::load_labelled;

/// Slowest and fastest level path a policy is asked to fly (m/s).
const SPEED_LIMITS_MPS: (f64, f64) = (1.0, 12.0);
/// Most gaits one run flies (each is 14 s of flight).
const MOST_GAITS: usize = 100_000;

/// `flapper power-curve`'s options.
#[derive(clap::Args)]
pub struct PowerCurveArgs {
    /// A trained policy to fly on the level paths; repeat the flag for several (none: the gaits alone).
    #[arg(long = "policy", value_name = "FILE")]
    pub policies: Vec<PathBuf>,
    /// The name of each --policy in the table and the figure, in the same order (default: the
    /// policy's folder name, or a checkpoint's file name).
    #[arg(long = "label", value_name = "NAME")]
    pub labels: Vec<String>,
    /// Speeds of the policies' level paths (m/s, comma-separated).
    #[arg(long = "speeds", value_delimiter = ',', default_value = "3,3.5,4,4.5,5,5.3,6,7", allow_hyphen_values = true)]
    pub speeds_mps: Vec<f64>,
    /// Flap frequencies of the gait family (Hz, comma-separated; default 4, 4.5, 5, 5.3, 5.6, 6).
    #[arg(long = "frequencies", value_delimiter = ',', allow_hyphen_values = true)]
    pub frequencies_hz: Option<Vec<f64>>,
    /// Body-pitch trims the gaits' tail holds (deg nose up, comma-separated; default -5 to 25 by 5).
    #[arg(long = "body-pitches", value_delimiter = ',', allow_hyphen_values = true)]
    pub body_pitches_deg: Option<Vec<f64>>,
    /// Wing-pitch amplitudes (deg, comma-separated; default 5 to 35 by 5).
    #[arg(long = "pitch-amplitudes", value_delimiter = ',', allow_hyphen_values = true)]
    pub pitch_amplitudes_deg: Option<Vec<f64>>,
    /// How far the wing pitch leads the flap (deg, comma-separated; default 0, 45, 90, the scripted
    /// gait's).
    #[arg(long = "pitch-leads", value_delimiter = ',', allow_hyphen_values = true)]
    pub pitch_leads_deg: Option<Vec<f64>>,
    /// Tail trims (deg, comma-separated; default -30 to 10 by 10).
    #[arg(long = "tail-trims", value_delimiter = ',', allow_hyphen_values = true)]
    pub tail_trims_deg: Option<Vec<f64>>,
    /// Episodes per policy and speed, each from its own randomized start (as `flapper eval`).
    #[arg(long, default_value_t = 20, value_parser = count, allow_negative_numbers = true)]
    pub episodes: usize,
    /// Seed of the randomized starts.
    #[arg(long, default_value_t = 11, value_parser = seed, allow_negative_numbers = true)]
    pub seed: u64,
    /// Output folder (created if needed).
    #[arg(long, default_value = "run/power-curve")]
    pub out: PathBuf,
}

pub fn power_curve_command(robot: &RobotModel, args: &PowerCurveArgs) -> Result<()> {
    let PowerCurveArgs { policies, labels, speeds_mps, episodes, seed, out, .. } = args;
    let family = gait_family(args)?;
    if *episodes == 0 || *episodes > 100_000 {
        bail!("--episodes must be 1 to 100000, got {episodes}");
    }
    let (slowest, fastest) = SPEED_LIMITS_MPS;
    if let Some(bad) = speeds_mps.iter().find(|v| !(v.is_finite() && (slowest..=fastest).contains(*v))) {
        bail!("--speeds: each speed must be {slowest} to {fastest} m/s, got {bad}");
    }
    if speeds_mps.is_empty() || speeds_mps.len() > 100 {
        bail!("--speeds: give 1 to 100 speeds, got {}", speeds_mps.len());
    }
    // Every policy is read before anything is flown: a bad file stops the command at once.
    let loaded = load_labelled(policies, labels)?;
    crate::output_dir::prepare_output_dir(out)?;
    let settings =
        PowerCurveSettings { family, policy_speeds_mps: speeds_mps.clone(), episodes: *episodes, seed: *seed };
    println!(
        "power curve of level flight: {} scripted gaits{}",
        settings.family.gaits().len(),
        if loaded.is_empty() {
            String::new()
        } else {
            format!(
                ", then {} on level paths, {episodes} episodes per speed from randomized starts (seed {seed})",
                loaded.len()
            )
        }
    );
    let began = std::time::Instant::now();
    let progress = crate::progress::Progress::new(step_count(&settings, loaded.len()), "steps");
    let curve = measure_power_curve(robot, &loaded, &settings, &|done: &str| progress.step_done(done))?;
    progress.finish();
    eprintln!("measured in {:.1} s", began.elapsed().as_secs_f64());
    print_tables(&curve);
    for path in write_power_curve(out, &curve)? {
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// The gait family the flags ask for, each list checked against its range: the default family's
/// list where a flag is not given.
fn gait_family(args: &PowerCurveArgs) -> Result<GaitFamily> {
    let default = GaitFamily::default();
    let list = |given: &Option<Vec<f64>>, default: Vec<f64>, flag: &str, (low, high): (f64, f64), unit: &str| {
        let values = given.clone().unwrap_or(default);
        if let Some(bad) = values.iter().find(|v| !(v.is_finite() && (low..=high).contains(*v))) {
            bail!("{flag}: each value must be {low} to {high} {unit}, got {bad}");
        }
        if values.is_empty() {
            bail!("{flag}: give at least one value");
        }
        Ok(values)
    };
    let family = GaitFamily {
        frequencies_hz: list(&args.frequencies_hz, default.frequencies_hz, "--frequencies", (0.5, 10.0), "Hz")?,
        body_pitches_deg: list(
            &args.body_pitches_deg,
            default.body_pitches_deg,
            "--body-pitches",
            (-45.0, 60.0),
            "deg",
        )?,
        pitch_amplitudes_deg: list(
            &args.pitch_amplitudes_deg,
            default.pitch_amplitudes_deg,
            "--pitch-amplitudes",
            (0.0, 60.0),
            "deg",
        )?,
        pitch_leads_deg: list(&args.pitch_leads_deg, default.pitch_leads_deg, "--pitch-leads", (-180.0, 180.0), "deg")?,
        tail_trims_deg: list(&args.tail_trims_deg, default.tail_trims_deg, "--tail-trims", (-60.0, 60.0), "deg")?,
    };
    let gaits = family.frequencies_hz.len()
        * family.body_pitches_deg.len()
        * family.pitch_amplitudes_deg.len()
        * family.pitch_leads_deg.len()
        * family.tail_trims_deg.len();
    if gaits > MOST_GAITS {
        bail!("the gait family has {gaits} gaits (the product of the five lists); at most {MOST_GAITS}");
    }
    Ok(family)
}

fn print_tables(curve: &PowerCurve) {
    println!();
    println!(
        "cheapest level gait per {SPEED_BIN_MPS} m/s of speed (altitude held within {LEVEL_TOLERANCE_M} m over {SETTLED_AFTER_S}-{GAIT_FLIGHT_S} s; of {} gaits, {} level):",
        curve.gaits.len(),
        curve.gaits.iter().filter(|g| g.level()).count()
    );
    println!(
        "{:>9} {:>6} {:>9} {:>8} {:>6} {:>7} {:>8} {:>8} {:>8}",
        "speed", "gaits", "power W", "J/m", "Hz", "pitch", "wing", "lead", "tail"
    );
    for c in &curve.cheapest {
        let f = &c.flight;
        println!(
            "{:>9.2} {:>6} {:>9.2} {:>8.3} {:>6.1} {:>7.0} {:>8.0} {:>8.0} {:>8.0}",
            f.speed_mps,
            c.level_gaits,
            f.power_w,
            f.energy_per_metre_j,
            f.gait.frequency_hz,
            f.gait.body_pitch_deg,
            f.gait.pitch_amplitude_deg,
            f.gait.pitch_lead_deg,
            f.gait.tail_trim_deg
        );
    }
    match curve.scripted_gait() {
        Some(s) => println!(
            "the scripted gait (5.3 Hz, nose 20 deg) flies level at {:.2} m/s, {:.2} W, {:.3} J/m",
            s.speed_mps, s.power_w, s.energy_per_metre_j
        ),
        None => println!("the scripted gait did not fly level on this robot"),
    }
    if curve.policies.is_empty() {
        return;
    }
    println!();
    println!(
        "policies on level paths ({} episodes per speed, seed {}; figures after {SETTLED_AFTER_S} s, of the completed episodes):",
        curve.episodes, curve.seed
    );
    println!(
        "{:<24} {:>6} {:>9} {:>9} {:>8} {:>8} {:>10} {:>10}",
        "policy", "path", "completed", "speed", "power W", "J/m", "x cheapest", "x scripted"
    );
    let ratio = |r: Option<f64>| r.map_or("-".to_owned(), |r| format!("{r:.2}"));
    for p in &curve.policies {
        println!(
            "{:<24} {:>6.1} {:>9} {:>9.2} {:>8.2} {:>8.3} {:>10} {:>10}",
            p.label,
            p.path_speed_mps,
            format!("{}/{}", p.completed, p.episodes),
            p.speed_mps,
            p.power_w,
            p.energy_per_metre_j,
            ratio(p.over_cheapest_gait),
            ratio(p.over_scripted_gait)
        );
    }
}

pub fn run(args: PowerCurveArgs, model: Option<&Path>) -> Result<()> {
    power_curve_command(&crate::robot::load(model)?, &args)
}
