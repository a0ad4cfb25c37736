//! `flapper`: the command line. It parses, validates and dispatches; the work happens in the
//! library crates. Errors reach the user as one line and a non-zero exit code.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};

mod bench;
mod curriculum;
mod eval;
mod export_policy;
mod flag_values;
mod fly;
mod frontier;
mod modes;
mod output_dir;
mod pendulum;
mod phase;
mod power_curve;
mod progress;
mod reference;
mod render;
mod report;
mod robot;
mod robustness;
mod sysid;
mod train;

#[derive(Parser)]
#[command(
    name = "flapper",
    version,
    about = "Learning-based trajectory tracking for a bird-inspired flapping-wing robot"
)]
struct Cli {
    /// Robot model (MJCF). Defaults to the shipped models/flapper.xml.
    #[arg(long, global = true, value_name = "FILE")]
    model: Option<PathBuf>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Fly a controller and write the flight as CSV and SVG plots.
    Fly(fly::FlyArgs),
    /// Show a reference trajectory (a name from the paper's results or your own CSV): write it
    /// resampled at 50 Hz as CSV, with top and side views.
    Reference(reference::ReferenceArgs),
    /// Train the final controller from scratch: every curriculum stage in turn, each checkpoint judged
    /// on a validation set, the best handed to the next stage, gates that stop a run which does not
    /// learn. With --model (a robot of your own), fine-tune the shipped controller on it with stages 4
    /// and 5 instead, unless --from-scratch. Run again on the same --out to continue after an interruption.
    Curriculum(curriculum::CurriculumArgs),
    /// Train a flight controller with PPO: a progress bar, one CSV row per iteration, learning curves,
    /// checkpoints every few iterations, and the final policy, all in --out.
    Train(train::TrainArgs),
    /// Evaluate trajectory tracking: fly a trained policy (and the scripted baseline, for comparison)
    /// on a reference from randomized starts; print a table, write per-step CSV and plots.
    Eval(eval::EvalArgs),
    /// Identify the closed loop (robot + policy) as third-order transfer functions from desired to
    /// flown position per axis (paper IV-A): poles, zeros, DC gain, validation fit, stability and
    /// minimum-phase verdicts; sysid.json, sysid_io.csv, pole-zero and validation plots.
    Sysid(sysid::SysidArgs),
    /// Phase portraits of the wings (paper IV-B, Fig. 6-7): right wing in cruise vs climb at 3 m/s, left
    /// vs right wing turning left (skipped for a policy that cannot turn); phase.json checks the
    /// paper's claims; phase_climb.svg, phase_turn.svg.
    Phase(phase::PhaseArgs),
    /// Flight modes on the longitudinal reference: flap amplitude, frequency and power in the cruise,
    /// climb, glide and dive segments, and whether the policy glides; modes.json, modes.svg.
    Modes(modes::ModesArgs),
    /// Energy against tracking (the efficient-bird trade-off): each policy and the scripted gait on
    /// longitudinal (energy per metre over the scripted gait's on the same starts, RMS error), with the
    /// glide fraction, the cruise flap frequency and the level 3.0 m/s path; a table, frontier.csv,
    /// energy_vs_tracking.svg and energy_vs_slow_flight.svg.
    Frontier(frontier::FrontierArgs),
    /// What straight and level flight costs at each airspeed: the scripted gait's family (frequency,
    /// trim, wing pitch, tail) flown level, the cheapest gait per airspeed, and policies on level paths
    /// beside it (energy per metre over the cheapest gait's); gaits.csv, power_curve.csv, power_curve.svg.
    PowerCurve(power_curve::PowerCurveArgs),
    /// Robustness sweeps (paper Fig. 8-9) on one reference: success as each fluid coefficient (and all
    /// five) is randomized over wider ranges, under constant winds, with all of Table III at once, and
    /// the level-flight airspeed envelope; robustness_fluid.csv, robustness_wind.csv, robustness.json,
    /// plots.
    Robustness(robustness::RobustnessArgs),
    /// Regenerate the paper: every experiment behind its figures with the shipped policies (tracking,
    /// system identification, phase portraits, robustness), rendered snapshots and a flight video, and
    /// one page comparing our numbers with the paper's: DIR/index.html and DIR/report.md.
    Report(report::ReportArgs),
    /// Render one flight with MuJoCo's offscreen renderer: a chase-camera video (MP4, needs ffmpeg)
    /// and snapshots overlaid along the manoeuvre with the reference drawn (PNG; needs EGL).
    Render(render::RenderArgs),
    /// Write a checkpoint's policy (networks, log-std, normalizer; no optimizer state) as a policy file,
    /// or a policy for a robot: ONNX, or one C99 header and source file (docs/deploy.md).
    ExportPolicy(export_policy::ExportPolicyArgs),
    /// Check the learner on the inverted pendulum (Gymnasium's InvertedPendulum): train one run per
    /// seed until the mean policy holds the pole for 1000 steps, and report the steps it took.
    Pendulum(pendulum::PendulumArgs),
    /// Time this model's MuJoCo steps and 20 ms control steps on one thread, the vectorized
    /// environments, the PPO update and PPO training end to end (medians over repeats).
    Bench(bench::BenchArgs),
}

fn main() -> ExitCode {
    // MuJoCo's messages go through `log` (silent by default) instead of stdout and MUJOCO_LOG.TXT.
    // SAFETY: called first thing, before any thread exists or MuJoCo is used.
    unsafe { mujoco_rs::prelude::install_logging_hook() };
    // Piped into `head` and the like, stop quietly when the reader goes away (as Unix tools do)
    // instead of panicking on the next print.
    // SAFETY: restores the default signal disposition before any thread exists.
    unsafe { libc::signal(libc::SIGPIPE, libc::SIG_DFL) };
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(error) if !error.use_stderr() => {
            // --help and --version
            let _ = error.print();
            return ExitCode::SUCCESS;
        }
        Err(error) => {
            // clap's whole message: what is wrong, the usage line, did-you-mean, valid values.
            let _ = error.print();
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // One line, whatever the message (MuJoCo's parser messages span several lines).
            let text = one_line(&error);
            eprintln!("error: {}", text.split_whitespace().collect::<Vec<_>>().join(" "));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by ": ", leaving out a cause whose message the text already holds
/// (many of our errors word their cause into their own message).
fn one_line(error: &anyhow::Error) -> String {
    let mut text = error.to_string();
    for cause in error.chain().skip(1) {
        let message = cause.to_string();
        if !text.contains(&message) {
            text = format!("{text}: {message}");
        }
    }
    text
}

fn run(cli: Cli) -> Result<()> {
    // Training's vector path may be forced narrower (docs/training.md); a wrong value is refused, not ignored.
    flapper_ppo::fixed_matmul::Simd::from_environment().map_err(anyhow::Error::msg)?;
    let model = cli.model.as_deref();
    match cli.command {
        Command::Fly(args) => fly::run(args, model),
        Command::Reference(args) => reference::run(args, model),
        Command::Curriculum(args) => curriculum::run(args, model),
        Command::Train(args) => train::run(args, model),
        Command::Eval(args) => eval::run(args, model),
        Command::Sysid(args) => sysid::run(args, model),
        Command::Phase(args) => phase::run(args, model),
        Command::Modes(args) => modes::run(args, model),
        Command::Frontier(args) => frontier::run(args, model),
        Command::PowerCurve(args) => power_curve::run(args, model),
        Command::Robustness(args) => robustness::run(args, model),
        Command::Report(args) => report::run(args, model),
        Command::Render(args) => render::run(args, model),
        Command::ExportPolicy(args) => export_policy::run(args, model),
        Command::Pendulum(args) => pendulum::run(args),
        Command::Bench(args) => bench::run(args, model),
    }
}
