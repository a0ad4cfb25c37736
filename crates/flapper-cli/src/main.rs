//! `flapper`: the command line. It parses, validates and dispatches; the work happens in the
//! library crates. Errors reach the user as one line and a non-zero exit code.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};
use flapper_sim::RobotModel;

mod bench;
mod curriculum;
mod eval;
mod export_policy;
mod fly;
mod modes;
mod output_dir;
mod phase;
mod progress;
mod reference;
mod report;
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
    Fly {
        /// Which controller flies the robot.
        #[arg(long, value_enum, default_value_t = fly::ControllerKind::Scripted)]
        controller: fly::ControllerKind,
        /// Flight duration in seconds.
        #[arg(long, default_value_t = 15.0, allow_negative_numbers = true)]
        seconds: f64,
        /// Output directory (created if needed).
        #[arg(long, default_value = "run/fly")]
        out: PathBuf,
        /// Tail angle of the glide controller in degrees (negative = trailing edge up).
        #[arg(long, default_value_t = -10.0, allow_negative_numbers = true)]
        tail_deg: f64,
    },
    /// Show a reference trajectory (a name from the paper's results or your own CSV): write it
    /// resampled at 50 Hz as CSV, with top and side views.
    Reference {
        /// A named reference (see --list) or a CSV file of time_s,x_m,y_m,z_m.
        #[arg(required_unless_present = "list")]
        reference: Option<String>,
        /// List the named references and exit.
        #[arg(long)]
        list: bool,
        /// Output directory (created if needed).
        #[arg(long, default_value = "run/reference")]
        out: PathBuf,
    },
    /// Train the final controller from scratch: every curriculum stage in turn, each checkpoint judged
    /// on a validation set, the best handed to the next stage, gates that stop a run which does not
    /// learn. Run again on the same --out to continue after an interruption.
    Curriculum(curriculum::CurriculumArgs),
    /// Train a flight controller with PPO: a progress bar, one CSV row per iteration, learning curves,
    /// checkpoints every few iterations, and the final policy, all in --out.
    Train {
        /// Run configuration (TOML with [runner], [ppo] and [task] tables; every key optional).
        #[arg(long, value_name = "TOML")]
        config: Option<PathBuf>,
        /// Curriculum stage 1-4 (replaces the config's task.stage).
        #[arg(long)]
        stage: Option<i64>,
        /// Run folder (created; must not hold a run unless --resume).
        #[arg(long)]
        out: PathBuf,
        /// Continue the run in --out from its latest checkpoint, with the config it started with.
        #[arg(long, conflicts_with_all = ["config", "stage", "init_from", "seed"])]
        resume: bool,
        /// Start from this policy or checkpoint (e.g. the previous stage's policy.safetensors).
        #[arg(long, value_name = "FILE")]
        init_from: Option<PathBuf>,
        /// Number of PPO iterations (replaces runner.iterations; with --resume, raises the target).
        #[arg(long)]
        iterations: Option<usize>,
        /// Random seed (replaces runner.seed).
        #[arg(long)]
        seed: Option<u64>,
        /// Parallel environments (replaces runner.envs).
        #[arg(long)]
        envs: Option<usize>,
    },
    /// Evaluate trajectory tracking: fly a trained policy (and the scripted baseline, for comparison)
    /// on a reference from randomized starts; print a table, write per-step CSV and plots.
    Eval {
        /// Trained policy (a run's policy.safetensors or a checkpoint). Without it only the scripted
        /// baseline flies.
        #[arg(long, value_name = "FILE")]
        policy: Option<PathBuf>,
        /// A named reference (see `flapper reference --list`) or a CSV file of time_s,x_m,y_m,z_m.
        #[arg(long, default_value = "longitudinal")]
        reference: String,
        /// Episodes, each from its own randomized start.
        #[arg(long, default_value_t = 100)]
        episodes: usize,
        /// Seed of the randomized starts.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output folder (created if needed): policy/ and scripted/ subfolders and summary.csv.
        #[arg(long, default_value = "run/eval")]
        out: PathBuf,
        /// Do not fly the scripted baseline.
        #[arg(long)]
        no_baseline: bool,
        /// Also write what each pilot saw and did in episode 0 (observations and actions, one row
        /// per control step) as PILOT/observations.csv: for checking another implementation.
        #[arg(long)]
        observations: bool,
    },
    /// Identify the closed loop (robot + policy) as third-order transfer functions from desired to
    /// flown position per axis (paper IV-A): poles, zeros, DC gain, validation fit, stability and
    /// minimum-phase verdicts; sysid.json, sysid_io.csv, pole-zero and validation plots.
    Sysid {
        /// Trained policy (a run's policy.safetensors or a checkpoint).
        #[arg(long, value_name = "FILE")]
        policy: PathBuf,
        /// Seed of the perturbations' phases (identification and validation records differ).
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// RMS of the target perturbation on each axis (m).
        #[arg(long, default_value_t = 0.15)]
        amplitude_m: f64,
        /// Take as input the desired position this far ahead (s, up to the 0.6 s the policy sees
        /// ahead); 0 is the paper's input, the current desired position.
        #[arg(long, default_value_t = 0.0)]
        input_lead_s: f64,
        /// Output folder (created if needed).
        #[arg(long, default_value = "run/sysid")]
        out: PathBuf,
    },
    /// Phase portraits of the wings (paper IV-B, Fig. 6-7): right wing in cruise vs climb at 3 m/s, left
    /// vs right wing turning left (skipped for a policy that cannot turn); phase.json checks the
    /// paper's claims; phase_climb.svg, phase_turn.svg.
    Phase {
        /// Trained policy (a run's policy.safetensors or a checkpoint).
        #[arg(long, value_name = "FILE")]
        policy: PathBuf,
        /// Forward speed of the cruise and the climb (the paper: 3 m/s).
        #[arg(long, default_value_t = 3.0)]
        speed_mps: f64,
        /// Output folder (created if needed).
        #[arg(long, default_value = "run/phase")]
        out: PathBuf,
    },
    /// Flight modes on the longitudinal reference: flap amplitude, frequency and power in the cruise,
    /// climb, glide and dive segments, and whether the policy glides; modes.json, modes.svg.
    Modes {
        /// Trained policy (a run's policy.safetensors or a checkpoint).
        #[arg(long, value_name = "FILE")]
        policy: PathBuf,
        /// Output folder (created if needed).
        #[arg(long, default_value = "run/modes")]
        out: PathBuf,
    },
    /// Robustness sweeps (paper Fig. 8-9) on one reference: success as each fluid coefficient (and all
    /// five) is randomized over wider ranges, under constant winds, with all of Table III at once, and
    /// the level-flight airspeed envelope; robustness_fluid.csv, robustness_wind.csv, robustness.json,
    /// plots.
    Robustness {
        /// Trained policy (a run's policy.safetensors or a checkpoint).
        #[arg(long, value_name = "FILE")]
        policy: PathBuf,
        /// A named reference (see `flapper reference --list`) or a CSV file of time_s,x_m,y_m,z_m.
        #[arg(long, default_value = "longitudinal")]
        reference: String,
        /// Episodes per setting, each from its own randomized start.
        #[arg(long, default_value_t = 100)]
        episodes: usize,
        /// Seed of the starts and of the drawn dynamics.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Which sweeps to run (comma-separated): fluid, wind, table3, envelope.
        #[arg(long, value_delimiter = ',', default_value = "fluid,wind,table3,envelope")]
        sweeps: Vec<String>,
        /// Randomization ranges r of the fluid sweep (comma-separated; coefficients x[1 - r, 1 + r]).
        /// Default: the paper's 0, 0.1, 0.2, 0.3, 0.4, 0.5.
        #[arg(long, value_delimiter = ',')]
        ranges: Option<Vec<f64>>,
        /// Output folder (created if needed).
        #[arg(long, default_value = "run/robustness")]
        out: PathBuf,
    },
    /// Regenerate the paper: every experiment behind its figures with the shipped policies (tracking,
    /// system identification, phase portraits, robustness), rendered snapshots and a flight video, and
    /// one page comparing our numbers with the paper's: DIR/index.html and DIR/report.md.
    Report {
        /// The controller the report shows (default: the final shipped controller).
        #[arg(long, value_name = "FILE", default_value = flapper_report::FINAL_POLICY)]
        policy: PathBuf,
        /// Randomized starts per named reference.
        #[arg(long, default_value_t = 100)]
        episodes: usize,
        /// Episodes per setting of the robustness sweeps (fluid coefficients, winds, Table III).
        #[arg(long, default_value_t = 50)]
        robustness_episodes: usize,
        /// Seed of the randomized starts and the drawn dynamics.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Skip the rendered snapshots and the video (everything else is written).
        #[arg(long)]
        no_pictures: bool,
        /// Output folder (created if needed).
        #[arg(long, default_value = "run/report")]
        out: PathBuf,
    },
    /// Render one flight with MuJoCo's offscreen renderer: a chase-camera video (MP4, needs ffmpeg)
    /// and snapshots overlaid along the manoeuvre with the reference drawn (PNG; needs EGL).
    Render {
        /// Trained policy (a run's policy.safetensors or a checkpoint).
        #[arg(long, value_name = "FILE")]
        policy: PathBuf,
        /// A named reference (see `flapper reference --list`) or a CSV file of time_s,x_m,y_m,z_m.
        #[arg(long, default_value = "aerobatic")]
        reference: String,
        /// Seed of the randomized start.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output folder (created if needed).
        #[arg(long, default_value = "run/render")]
        out: PathBuf,
    },
    /// Write a checkpoint's policy (networks, log-std, normalizer; no optimizer state) as a policy file.
    ExportPolicy {
        /// A checkpoint (runs/NAME/checkpoints/iter_NNNNNN.safetensors).
        #[arg(long, value_name = "FILE")]
        checkpoint: PathBuf,
        /// The policy file to write (must not exist).
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
    },
    /// Check the learner on the inverted pendulum (Gymnasium's InvertedPendulum): train one run per
    /// seed until the mean policy holds the pole for 1000 steps, and report the steps it took.
    Pendulum {
        /// Seeds to train (one run each).
        #[arg(long, value_delimiter = ',', default_value = "1,2,3,4,5")]
        seeds: Vec<u64>,
        /// Give up after this many iterations (64 environments x 24 steps each).
        #[arg(long, default_value_t = 400)]
        max_iterations: usize,
        /// Output folder (one run folder per seed; replaced if it exists).
        #[arg(long, default_value = "run/pendulum")]
        out: PathBuf,
    },
    /// Time this model's MuJoCo steps and 20 ms control steps on one thread, the vectorized
    /// environments, the PPO update and PPO training end to end (medians over repeats).
    Bench {
        /// Number of timed blocks (the median over blocks is reported).
        #[arg(long, default_value_t = 21)]
        blocks: usize,
        /// MuJoCo steps per block.
        #[arg(long, default_value_t = 5000)]
        steps: usize,
        /// Also time this many vectorized environments (0 = skip).
        #[arg(long, default_value_t = 256)]
        envs: usize,
        /// Worker threads for the environments (0 = one per core).
        #[arg(long, default_value_t = 0)]
        threads: usize,
        /// Also time this many PPO iterations end to end on the flight task (0 = skip).
        #[arg(long, default_value_t = 10)]
        train_iterations: usize,
    },
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
            let message = error.render().to_string();
            let first = message.lines().next().unwrap_or("invalid arguments").trim_start_matches("error: ");
            eprintln!("error: {first} (see 'flapper --help')");
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            // One line, whatever the message (MuJoCo's parser messages span several lines).
            let text = format!("{error:#}");
            eprintln!("error: {}", text.split_whitespace().collect::<Vec<_>>().join(" "));
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    let robot = match &cli.model {
        Some(path) => RobotModel::load(path)?,
        None => RobotModel::flapper()?,
    };
    match cli.command {
        Command::Fly { controller, seconds, out, tail_deg } => {
            fly::fly_command(&robot, controller, seconds, tail_deg, &out)
        }
        Command::Reference { reference, list, out } => {
            reference::reference_command(&robot, reference.as_deref(), list, &out)
        }
        Command::Bench { blocks, steps, envs, threads, train_iterations } => {
            bench::bench_command(&robot, blocks, steps, envs, threads, train_iterations)
        }
        Command::Curriculum(args) => curriculum::run(&robot, args),
        Command::Train { config, stage, out, resume, init_from, iterations, seed, envs } => {
            let overrides = train::Overrides { iterations, seed, envs };
            train::train_command(&robot, config.as_deref(), stage, &out, resume, init_from, overrides)
        }
        Command::Eval { policy, reference, episodes, seed, out, no_baseline, observations } => {
            let args = eval::EvalArgs {
                policy: policy.as_deref(),
                reference: &reference,
                episodes,
                seed,
                out: &out,
                baseline: !no_baseline,
                observations,
            };
            eval::eval_command(&robot, args)
        }
        Command::ExportPolicy { checkpoint, out } => export_policy::export_policy_command(&checkpoint, &out),
        Command::Phase { policy, speed_mps, out } => phase::phase_command(&robot, &policy, speed_mps, &out),
        Command::Modes { policy, out } => modes::modes_command(&robot, &policy, &out),
        Command::Robustness { policy, reference, episodes, seed, sweeps, ranges, out } => {
            robustness::robustness_command(
                &robot,
                robustness::RobustnessArgs {
                    policy: &policy,
                    reference: &reference,
                    episodes,
                    seed,
                    sweeps: &sweeps,
                    ranges: ranges.as_deref(),
                    out: &out,
                },
            )
        }
        Command::Sysid { policy, seed, amplitude_m, input_lead_s, out } => {
            sysid::sysid_command(&robot, &policy, seed, amplitude_m, input_lead_s, &out)
        }
        Command::Report { policy, episodes, robustness_episodes, seed, no_pictures, out } => {
            let settings = flapper_report::ReportSettings {
                policy,
                episodes,
                robustness_episodes,
                seed,
                pictures: !no_pictures,
                ..Default::default()
            };
            report::report_command(&robot, &settings, &out)
        }
        Command::Render { policy, reference, seed, out } => {
            report::render_command(&robot, &policy, &reference, seed, &out)
        }
        Command::Pendulum { seeds, max_iterations, out } => train::pendulum_command(&seeds, max_iterations, &out),
    }
}
