//! `flapper curriculum`: train the final controller from scratch, every stage in turn, unattended (or,
//! for a robot of one's own, fine-tune the shipped controller on it); run again on the same folder to
//! continue after an interruption.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use flapper_curriculum::run::describe_gate;
use flapper_curriculum::selection::{StageOutcome, StoppedStage};
use flapper_curriculum::summary::Summary;
use flapper_curriculum::{CurriculumConfig, CurriculumError, CurriculumRequest, Progress, run_curriculum};

use crate::flag_values::seed;

/// The shipped curriculum, relative to the repository (the default `--config`).
const SHIPPED_CONFIG: &str = "configs/curriculum.toml";
/// Stages 4 and 5 alone, to fine-tune a controller (the shipped one) on another robot: what `--model`
/// runs unless `--from-scratch`.
const TRANSFER_CONFIG: &str = "configs/curriculum-transfer.toml";

#[derive(clap::Args)]
pub struct CurriculumArgs {
    /// Run folder: one subfolder per stage, summary.json, curriculum.svg and the final policy.safetensors.
    /// Give the same folder again to continue an interrupted run.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// The curriculum (TOML: seed, shared [runner] and [ppo], one [[stages]] entry per stage).
    /// [default: configs/curriculum.toml; with --model, configs/curriculum-transfer.toml from the shipped
    /// controller]
    #[arg(long, value_name = "TOML")]
    config: Option<PathBuf>,
    /// Replaces the config's seed (stage k trains with seed * 100 + k).
    #[arg(long, value_parser = seed, allow_negative_numbers = true)]
    seed: Option<u64>,
    /// Start the first stage from this policy (a policy.safetensors, or a checkpoint) instead of new
    /// networks, with that stage's start_noise_std: fine-tunes a controller, for example the shipped one
    /// on your robot with configs/curriculum-transfer.toml (stages 4 and 5 only).
    #[arg(long, value_name = "POLICY")]
    init_from: Option<PathBuf>,
    /// With --model: train every stage of configs/curriculum.toml from new networks instead of fine-tuning
    /// the shipped controller on the robot (stages 4 and 5). From scratch, 4 of the 8 robots of
    /// examples/robots/ trained so got no controller; the fine-tune trained those 4 and 2 more
    /// (docs/training.md, "Training your own robot").
    #[arg(long, conflicts_with = "init_from")]
    from_scratch: bool,
    /// Stop after this stage (1-based); run again without it to go on.
    #[arg(long, value_name = "K", value_parser = 1..=100, allow_negative_numbers = true)]
    until_stage: Option<i64>,
}

/// Where a run starts: its curriculum and the policy its first stage starts from (`None`: new networks).
#[derive(Debug, PartialEq)]
struct Start {
    config: PathBuf,
    init_from: Option<PathBuf>,
    /// The shipped controller fine-tuned on a robot of one's own (`--model` without `--from-scratch`).
    transfer: bool,
}

/// Decides the start from the flags: a given `--config` or `--init-from` as given; otherwise a robot of
/// one's own (a `--model` that is not the shipped robot) fine-tunes the shipped controller unless
/// `--from-scratch`, and the shipped robot trains the shipped curriculum from scratch.
fn start(args: &CurriculumArgs, model: Option<&Path>) -> Result<Start> {
    let own_robot = match model {
        Some(path) => !is_shipped_robot(path),
        None if args.from_scratch => anyhow::bail!(
            "--from-scratch is for a robot of your own (--model FILE); the shipped robot always trains from scratch"
        ),
        None => false,
    };
    let shipped = |file: &str| flapper_report::shipped_file(file);
    Ok(match (&args.config, &args.init_from) {
        (Some(config), init_from) => Start { config: config.clone(), init_from: init_from.clone(), transfer: false },
        (None, Some(init_from)) => {
            Start { config: shipped(SHIPPED_CONFIG), init_from: Some(init_from.clone()), transfer: false }
        }
        (None, None) if own_robot && !args.from_scratch => Start {
            config: shipped(TRANSFER_CONFIG),
            init_from: Some(shipped(flapper_report::FINAL_POLICY)),
            transfer: true,
        },
        (None, None) => Start { config: shipped(SHIPPED_CONFIG), init_from: None, transfer: false },
    })
}

/// Whether `--model` names the shipped robot (the same bytes as `models/flapper.xml`): it trains from
/// scratch like no `--model` at all. A file that cannot be read is not; loading it says why.
fn is_shipped_robot(model: &Path) -> bool {
    std::fs::read(model).is_ok_and(|bytes| bytes == flapper_sim::ROBOT_MJCF.as_bytes())
}

pub fn run(args: CurriculumArgs, model: Option<&Path>) -> Result<()> {
    let robot = &crate::robot::load(model)?;
    let start = start(&args, model)?;
    let mut config = CurriculumConfig::load(&start.config)?;
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    // The command as a reader would type it: `flapper` whatever the binary's file is called.
    let command = std::iter::once("flapper".to_owned()).chain(std::env::args().skip(1)).collect::<Vec<_>>().join(" ");
    if let Some(policy) = &start.init_from {
        flapper_ppo::checkpoint::load(policy).with_context(|| match start.transfer {
            true => format!(
                "the shipped controller '{}', which --model fine-tunes on your robot, is not readable (--from-scratch \
                 needs none)",
                policy.display()
            ),
            false => format!("--init-from '{}' is not a policy or checkpoint", policy.display()),
        })?;
    }
    if start.transfer {
        println!(
            "a robot of your own: fine-tuning the shipped controller ({}) on it with the shipped curriculum's \
             stages 4 and 5 ({}); --from-scratch trains every stage from new networks instead",
            flapper_report::FINAL_POLICY,
            TRANSFER_CONFIG
        );
    }
    let until_stage = args.until_stage.map(|k| k as usize);
    let from_scratch = start.init_from.is_none();
    let request = CurriculumRequest { dir: &args.out, config, until_stage, command, init_from: start.init_from };
    let outcomes = run_curriculum(robot, request, &mut report_progress)
        .map_err(|error| match (&error, model) {
            (CurriculumError::GateMissed { .. }, Some(model)) if from_scratch && !is_shipped_robot(model) => {
                anyhow::anyhow!("{error}{}", transfer_hint(model, &args.out))
            }
            (CurriculumError::GateMissed { .. }, Some(model)) if start.transfer => {
                anyhow::anyhow!("{error}{}", from_scratch_hint(model, &args.out))
            }
            (CurriculumError::StartedStageChanged { .. }, Some(_)) if start.transfer => anyhow::anyhow!(
                "{error}. A folder started from scratch on a robot of your own (as --model did before \
                 2026-11-29) continues with --from-scratch"
            ),
            _ => anyhow::Error::new(error),
        })
        .with_context(|| format!("curriculum in '{}'", args.out.display()))?;
    let summary = Summary::read(&args.out)?;
    println!(
        "done: {} stages handed over a controller{}, {:.2} M environment steps, {:.0} s",
        outcomes.len(),
        summary.optional_stage_missed.as_ref().map_or(String::new(), optional_stage_note),
        summary.total_env_steps as f64 / 1e6,
        summary.total_wall_time_s
    );
    for file in ["policy.safetensors", "summary.json", "curriculum.svg"] {
        println!("wrote {}", args.out.join(file).display());
    }
    Ok(())
}

/// The final line's note on an optional last stage the run ended without: it trained and missed its gate,
/// or the budget left it no iteration to train (`iterations` 0; the reason is in `stopped_because`).
fn optional_stage_note(missed: &StoppedStage) -> String {
    if missed.iterations == 0 {
        format!(" (stage {} could not start: the environment-step budget was spent before it)", missed.stage)
    } else {
        format!(" (stage {} missed its gate)", missed.stage)
    }
}

/// What a robot of one's own whose run from scratch stopped at a gate can do next: the shipped controller
/// fine-tuned on it (stages 4 and 5, what `--model` runs without `--from-scratch`), the command spelled out.
fn transfer_hint(model: &Path, out: &Path) -> String {
    format!(
        ". For a robot of your own, the shipped controller fine-tuned on it may fly where training from scratch \
         stopped (it trained heavy.xml, wide.xml, narrow.xml and nose-heavy.xml of examples/robots/): flapper \
         curriculum --model {} --out {}",
        model.display(),
        sibling(out, "transfer").display()
    )
}

/// What a robot of one's own whose fine-tune of the shipped controller stopped at a gate can do next:
/// train every stage from scratch (which trained light.xml, soft-servos.xml, stiff-servos.xml and
/// tail-heavy.xml of examples/robots/).
fn from_scratch_hint(model: &Path, out: &Path) -> String {
    format!(
        ". The fine-tune of the shipped controller stopped; training every stage from new networks may fly \
         where it did not: flapper curriculum --model {} --from-scratch --out {}",
        model.display(),
        sibling(out, "from-scratch").display()
    )
}

/// `DIR-suffix` beside the run folder `DIR`: where the next attempt goes without touching this one.
fn sibling(out: &Path, suffix: &str) -> PathBuf {
    let name = out.file_name().map_or_else(|| "run".into(), |name| name.to_string_lossy());
    out.with_file_name(format!("{name}-{suffix}"))
}

/// What a stage's hand-over line adds when the checkpoint misses a sought bar (`selected.json` says
/// which), the most important first.
fn hand_over_warning(outcome: &StageOutcome) -> &'static str {
    let missed = |met: Option<bool>| met == Some(false);
    if missed(outcome.randomized_met) && missed(outcome.rms_met) {
        "; warning: no checkpoint met the randomized entries or the RMS bars within the budget, this one completes \
         every named reference the best (its scores are in selection.csv)"
    } else if missed(outcome.randomized_met) {
        "; warning: no checkpoint met the randomized entries within the budget, this one completes every named \
         reference the best (its scores are in selection.csv)"
    } else if missed(outcome.rms_met) {
        "; warning: no checkpoint met the RMS bars within the budget, this one completes every reference the best \
         (its errors are in selection.csv)"
    } else if missed(outcome.flight_modes_met) {
        "; warning: no checkpoint met the flight-mode bars (energy, glide, flap frequency) within the budget, this \
         one tracks every reference the most efficiently"
    } else if missed(outcome.identification_met) {
        "; warning: no checkpoint met the identification bar within the budget, this one flies every other bar \
         (its fit is in selection.csv)"
    } else {
        ""
    }
}

fn report_progress(event: Progress) {
    match event {
        Progress::StageStarts { stage, of, config, iterations, resumed_at } => {
            let from = if resumed_at > 0 { format!(", resuming at iteration {resumed_at}") } else { String::new() };
            println!(
                "stage {stage}/{of} ({}): up to {} iterations, validated every {}; gate: {}{from}",
                config.name,
                iterations,
                config.validate_every,
                describe_gate(&config.gate)
            );
        }
        Progress::Iteration { stage, log } => {
            if log.iteration.is_multiple_of(10) {
                eprintln!(
                    "  stage {stage} it {}  {:.2}M steps  {:.0} steps/s  return {}  std {:.2}  lr {:.1e}",
                    log.iteration,
                    log.env_steps as f64 / 1e6,
                    log.steps_per_s,
                    crate::progress::episode_mean(log.mean_return, 1),
                    log.update.action_std,
                    log.update.learning_rate
                );
            }
        }
        Progress::Validated { stage, row, gate_met } => {
            let per: Vec<String> = row
                .score
                .references
                .iter()
                .map(|r| {
                    let energy = r.energy_ratio.map_or(String::new(), |ratio| format!(" {ratio:.2} x"));
                    format!("{} {}/{} {:.2} m{energy}", r.name, r.completed, r.episodes, r.mean_rms_m)
                })
                .collect();
            let glide = match row.modes {
                Some(f) => format!(
                    "; glide fraction {:.2}, energy {:.2} x scripted, cruise flap {:.2} Hz",
                    f.glide_fraction, f.energy_ratio, f.cruise_flap_hz
                ),
                None => String::new(),
            };
            let identified = match row.identification_fit_percent {
                Some([x, y, z]) => format!("; identified fit x {x:.1}%, y {y:.1}%, z {z:.1}%"),
                None => String::new(),
            };
            println!(
                "  stage {stage} validation at iteration {}: {:.1}% completed, RMS {:.3} m ({}){glide}{identified}{}",
                row.iteration,
                row.score.completed_percent,
                row.score.mean_rms_m,
                per.join(", "),
                if gate_met { "; gate met" } else { "" }
            );
        }
        Progress::StageExtended { stage, extension } => println!(
            "stage {stage}: budget of {} iterations spent without meeting the gate, {}; {} iterations more",
            extension.at_iteration, extension.reason, extension.added_iterations
        ),
        Progress::StageDone { outcome } => println!(
            "stage {} ({}) done: {} iterations, {:.2} M steps, {:.0} s; hands over iteration {} ({:.1}% completed, RMS {:.3} m{}){}",
            outcome.stage,
            outcome.name,
            outcome.iterations,
            outcome.env_steps as f64 / 1e6,
            outcome.wall_time_s,
            outcome.selected_iteration,
            outcome.validation_score,
            outcome.validation_rms_m,
            match (outcome.glide_fraction, outcome.energy_ratio, outcome.cruise_flap_hz) {
                (Some(glide), Some(energy), Some(hz)) =>
                    format!(", glide fraction {glide:.2}, energy {energy:.2} x scripted, cruise flap {hz:.2} Hz"),
                _ => String::new(),
            },
            hand_over_warning(outcome)
        ),
        Progress::OptionalStageMissed { missed, kept } => println!(
            "{missed}. The stage is optional: the run ends with stage {}'s controller (iteration {}, {:.1}% completed, RMS {:.3} m), and summary.json records the missed stage (optional_stage_missed)",
            kept.stage, kept.selected_iteration, kept.validation_score, kept.validation_rms_m
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An optional stage that trained and missed its gate, and one the budget never let start, are told
    /// apart on the final line.
    #[test]
    fn the_final_line_says_whether_the_optional_stage_trained_or_could_not_start() {
        let mut missed = StoppedStage {
            stage: 6,
            name: "light feathering".into(),
            gate: "every validation reference completed".into(),
            iterations: 300,
            env_steps: 1_843_200,
            wall_time_s: 250.0,
            best_iteration: Some(100),
            best_validation_score: Some(97.0),
            best_validation_rms_m: Some(0.43),
            cpu: None,
            extensions: Vec::new(),
            stopped_because: None,
        };
        assert_eq!(optional_stage_note(&missed), " (stage 6 missed its gate)");
        missed.iterations = 0;
        missed.env_steps = 0;
        assert!(optional_stage_note(&missed).contains("stage 6 could not start"), "{}", optional_stage_note(&missed));
    }

    fn repository(file: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(file)
    }

    fn args(config: Option<&str>, init_from: Option<&str>, from_scratch: bool) -> CurriculumArgs {
        CurriculumArgs {
            out: "run".into(),
            config: config.map(PathBuf::from),
            seed: None,
            init_from: init_from.map(PathBuf::from),
            until_stage: None,
            from_scratch,
        }
    }

    /// `--model` with a robot of one's own fine-tunes the shipped controller (the transfer config from
    /// policies/final); `--from-scratch`, the shipped robot (by its bytes, wherever the file lies), or no
    /// `--model` train the shipped curriculum from new networks; a given `--config` or `--init-from` is
    /// taken as given.
    #[test]
    fn a_robot_of_one_s_own_fine_tunes_the_shipped_controller_unless_from_scratch() {
        let heavy = repository("examples/robots/heavy.xml");
        let scratch =
            |config: &str| Start { config: flapper_report::shipped_file(config), init_from: None, transfer: false };
        let transfer = Start {
            config: flapper_report::shipped_file(TRANSFER_CONFIG),
            init_from: Some(flapper_report::shipped_file(flapper_report::FINAL_POLICY)),
            transfer: true,
        };
        assert_eq!(start(&args(None, None, false), None).unwrap(), scratch(SHIPPED_CONFIG));
        assert_eq!(start(&args(None, None, false), Some(&heavy)).unwrap(), transfer);
        assert!(transfer.config.is_file() && transfer.init_from.as_ref().unwrap().is_file());
        assert_eq!(start(&args(None, None, true), Some(&heavy)).unwrap(), scratch(SHIPPED_CONFIG));

        let copy = std::env::temp_dir().join(format!("flapper-shipped-robot-{}.xml", std::process::id()));
        std::fs::write(&copy, flapper_sim::ROBOT_MJCF).unwrap();
        assert_eq!(start(&args(None, None, false), Some(&copy)).unwrap(), scratch(SHIPPED_CONFIG), "the shipped robot");
        std::fs::write(&copy, flapper_sim::ROBOT_MJCF.replacen("<mujoco", "<!-- mine -->\n<mujoco", 1)).unwrap();
        assert_eq!(start(&args(None, None, false), Some(&copy)).unwrap(), transfer, "another file is one's own");
        std::fs::remove_file(&copy).unwrap();

        let given = start(&args(Some("mine.toml"), None, false), Some(&heavy)).unwrap();
        assert_eq!(given, Start { config: "mine.toml".into(), init_from: None, transfer: false });
        let given = start(&args(None, Some("p.safetensors"), false), Some(&heavy)).unwrap();
        assert_eq!(given.init_from, Some("p.safetensors".into()));
        assert_eq!(given.config, flapper_report::shipped_file(SHIPPED_CONFIG));

        let refused = start(&args(None, None, true), None).unwrap_err().to_string();
        assert!(refused.contains("--from-scratch is for a robot of your own (--model FILE)"), "{refused}");
    }
}
