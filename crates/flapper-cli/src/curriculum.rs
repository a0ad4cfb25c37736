//! `flapper curriculum`: train the final controller from scratch, every stage in turn, unattended; run
//! again on the same folder to continue after an interruption.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use flapper_curriculum::run::describe_gate;
use flapper_curriculum::summary::Summary;
use flapper_curriculum::{CurriculumConfig, CurriculumError, CurriculumRequest, Progress, run_curriculum};

use crate::flag_values::seed;

/// The shipped curriculum, relative to the repository (the default `--config`).
const SHIPPED_CONFIG: &str = "configs/curriculum.toml";
/// Stages 4 and 5 alone, to fine-tune a controller (the shipped one) on another robot.
const TRANSFER_CONFIG: &str = "configs/experiments/curriculum-transfer.toml";

#[derive(clap::Args)]
pub struct CurriculumArgs {
    /// Run folder: one subfolder per stage, summary.json, curriculum.svg and the final policy.safetensors.
    /// Give the same folder again to continue an interrupted run.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// The curriculum (TOML: seed, shared [runner] and [ppo], one [[stages]] entry per stage).
    #[arg(long, value_name = "TOML", default_value = SHIPPED_CONFIG)]
    config: PathBuf,
    /// Replaces the config's seed (stage k trains with seed * 100 + k).
    #[arg(long, value_parser = seed, allow_negative_numbers = true)]
    seed: Option<u64>,
    /// Start the first stage from this policy (a policy.safetensors, or a checkpoint) instead of new
    /// networks, with that stage's start_noise_std: fine-tunes a controller, for example the shipped one
    /// on your robot with configs/experiments/curriculum-transfer.toml (stages 4 and 5 only).
    #[arg(long, value_name = "POLICY")]
    init_from: Option<PathBuf>,
    /// Stop after this stage (1-based); run again without it to go on.
    #[arg(long, value_name = "K", value_parser = 1..=100, allow_negative_numbers = true)]
    until_stage: Option<i64>,
}

pub fn run(args: CurriculumArgs, model: Option<&Path>) -> Result<()> {
    let robot = &crate::robot::load(model)?;
    let path = if args.config == Path::new(SHIPPED_CONFIG) {
        flapper_report::shipped_file(SHIPPED_CONFIG)
    } else {
        args.config
    };
    let mut config = CurriculumConfig::load(&path)?;
    if let Some(seed) = args.seed {
        config.seed = seed;
    }
    // The command as a reader would type it: `flapper` whatever the binary's file is called.
    let command = std::iter::once("flapper".to_owned()).chain(std::env::args().skip(1)).collect::<Vec<_>>().join(" ");
    if let Some(policy) = &args.init_from {
        flapper_ppo::checkpoint::load(policy)
            .with_context(|| format!("--init-from '{}' is not a policy or checkpoint", policy.display()))?;
    }
    let until_stage = args.until_stage.map(|k| k as usize);
    let from_scratch = args.init_from.is_none();
    let request = CurriculumRequest { dir: &args.out, config, until_stage, command, init_from: args.init_from };
    let outcomes = run_curriculum(robot, request, &mut report_progress)
        .map_err(|error| match (&error, model) {
            (CurriculumError::GateMissed { .. }, Some(model)) if from_scratch => {
                anyhow::anyhow!("{error}{}", transfer_hint(model, &args.out))
            }
            _ => anyhow::Error::new(error),
        })
        .with_context(|| format!("curriculum in '{}'", args.out.display()))?;
    let summary = Summary::read(&args.out)?;
    println!(
        "done: {} stages handed over a controller{}, {:.2} M environment steps, {:.0} s",
        outcomes.len(),
        summary
            .optional_stage_missed
            .as_ref()
            .map_or(String::new(), |m| format!(" (stage {} missed its gate)", m.stage)),
        summary.total_env_steps as f64 / 1e6,
        summary.total_wall_time_s
    );
    for file in ["policy.safetensors", "summary.json", "curriculum.svg"] {
        println!("wrote {}", args.out.join(file).display());
    }
    Ok(())
}

/// What a robot of one's own whose run from scratch stopped at a gate can do next: the shipped controller
/// fine-tuned on it (stages 4 and 5), the command spelled out.
fn transfer_hint(model: &Path, out: &Path) -> String {
    let name = out.file_name().map_or_else(|| "run".into(), |name| name.to_string_lossy());
    format!(
        ". For a robot of your own, the shipped controller fine-tuned on it may fly where training from scratch \
         stopped (it trained heavy.xml, wide.xml and nose-heavy.xml of examples/robots/): flapper curriculum \
         --config {} --model {} --init-from {} --out {}",
        flapper_report::shipped_file(TRANSFER_CONFIG).display(),
        model.display(),
        flapper_report::shipped_file(flapper_report::FINAL_POLICY).display(),
        out.with_file_name(format!("{name}-transfer")).display()
    )
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
                    "  stage {stage} it {}  {:.2}M steps  {:.0} steps/s  return {:.1}  std {:.2}  lr {:.1e}",
                    log.iteration,
                    log.env_steps as f64 / 1e6,
                    log.steps_per_s,
                    log.mean_return,
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
                .map(|r| format!("{} {}/{} {:.2} m", r.name, r.completed, r.episodes, r.mean_rms_m))
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
            match (outcome.rms_met, outcome.flight_modes_met, outcome.identification_met) {
                (Some(false), _, _) =>
                    "; warning: no checkpoint met the RMS bars within the budget, this one completes every reference the best (its errors are in selection.csv)",
                (_, Some(false), _) =>
                    "; warning: no checkpoint met the flight-mode bars (energy, glide, flap frequency) within the budget, this one tracks every reference the most efficiently",
                (_, _, Some(false)) =>
                    "; warning: no checkpoint met the identification bar within the budget, this one flies every other bar (its fit is in selection.csv)",
                _ => "",
            }
        ),
        Progress::OptionalStageMissed { missed, kept } => println!(
            "{missed}. The stage is optional: the run ends with stage {}'s controller (iteration {}, {:.1}% completed, RMS {:.3} m), and summary.json records the missed stage (optional_stage_missed)",
            kept.stage, kept.selected_iteration, kept.validation_score, kept.validation_rms_m
        ),
    }
}
