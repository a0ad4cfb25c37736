//! `flapper fly`: a scripted gait or an unpowered glide, without any learning: the robot and its
//! aerodynamics on their own.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::ValueEnum;
use flapper_eval::{
    Controller, FlightSpec, GlideController, ScriptedGait, ScriptedGaitConfig, fly, write_flight_plots,
};
use flapper_sim::RobotModel;

#[derive(Clone, Copy, ValueEnum)]
pub enum ControllerKind {
    /// The scripted 5.3 Hz flapping gait with pitch, roll and altitude feedback.
    Scripted,
    /// Wings flat, tail fixed (--tail-deg): an unpowered glide.
    Glide,
}

pub fn fly_command(robot: &RobotModel, kind: ControllerKind, seconds: f64, tail_deg: f64, out: &Path) -> Result<()> {
    if !(seconds.is_finite() && seconds > 0.0 && seconds <= 3600.0) {
        bail!("--seconds must be more than 0 and at most 3600, got {seconds}");
    }
    if !(-40.0..=40.0).contains(&tail_deg) {
        bail!("--tail-deg must be within the tail's range of -40..40 deg, got {tail_deg}");
    }
    let (mut controller, spec, name): (Box<dyn Controller>, FlightSpec, &str) = match kind {
        ControllerKind::Scripted => (
            Box::new(ScriptedGait::new(ScriptedGaitConfig::default())),
            FlightSpec::cruise_launch(seconds, ScriptedGaitConfig::default().body_pitch_deg),
            "scripted gait",
        ),
        ControllerKind::Glide => (
            Box::new(GlideController { tail_rad: tail_deg.to_radians() }),
            FlightSpec::cruise_launch(seconds, 7.5),
            "glide",
        ),
    };
    crate::output_dir::prepare_output_dir(out)?;
    let log = fly(robot, controller.as_mut(), &spec)?;
    let csv = out.join("flight.csv");
    log.write_csv(&csv)?;
    let plots = write_flight_plots(&log, out, name)?;
    let s = log.summary();
    println!("{name}: {:.2} s flown{}", s.duration_s, log.fault().map_or(String::new(), |f| format!(", stopped: {f}")));
    println!(
        "  altitude change      {:+.3} m (largest deviation {:.3} m)",
        s.altitude_change_m, s.max_altitude_deviation_m
    );
    println!(
        "  distance             {:.1} m, mean speed {:.2} m/s, mean airspeed {:.2} m/s",
        s.horizontal_distance_m, s.mean_speed_mps, s.mean_airspeed_mps
    );
    if s.altitude_change_m < -0.01 {
        println!("  glide ratio          {:.2}", s.horizontal_distance_m / -s.altitude_change_m);
    }
    println!(
        "  mechanical power     {:.2} W net, {:.2} W absolute",
        s.mean_mechanical_power_w, s.mean_absolute_power_w
    );
    println!("wrote {}", csv.display());
    for plot in plots {
        println!("wrote {}", plot.display());
    }
    Ok(())
}

/// `flapper fly`'s options.
#[derive(clap::Args)]
pub struct FlyArgs {
    /// Which controller flies the robot.
    #[arg(long, value_enum, default_value_t = ControllerKind::Scripted)]
    pub controller: ControllerKind,
    /// Flight duration in seconds.
    #[arg(long, default_value_t = 15.0, allow_negative_numbers = true)]
    pub seconds: f64,
    /// Output directory (created if needed).
    #[arg(long, default_value = "run/fly")]
    pub out: PathBuf,
    /// Tail angle of the glide controller in degrees (negative = trailing edge up).
    #[arg(long, default_value_t = -10.0, allow_negative_numbers = true)]
    pub tail_deg: f64,
}

pub fn run(args: FlyArgs, model: Option<&Path>) -> Result<()> {
    fly_command(&crate::robot::load(model)?, args.controller, args.seconds, args.tail_deg, &args.out)
}
