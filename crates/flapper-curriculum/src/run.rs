//! Running the curriculum into one folder, stage after stage, and continuing it after any interruption.
//!
//! Folder: `curriculum.toml` (the curriculum as run), `stageK/` (an ordinary training run, plus its
//! `selection.csv` and, once the stage is done, `selected.json`), `summary.json`, `curriculum.svg` and,
//! at the end, `policy.safetensors` (the last handed-over checkpoint as a policy file).
//!
//! A stage trains until its gate is met at a validation (from `min_iterations` on) or its budget is
//! spent; a stage whose budget ran out while its validations still improve is given more iterations
//! (`stageK/extensions.json`; at most [`MAX_EXTENSIONS`], within the run's budget after the later stages'),
//! else it stops the run (an optional stage instead ends it with the stage before it). It hands over
//! its best validated checkpoint (never simply the last), and the next stage starts from that checkpoint
//! with its own action noise. Running again on the same folder picks up where it
//! stopped: finished stages are read back, an interrupted one resumes from its last checkpoint (exactly,
//! as `flapper train --resume` does), a checkpoint saved but not yet judged is judged first.

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use flapper_ppo::checkpoint;
use flapper_ppo::run_folder::{RUN_FILES, checkpoint_path, saved_checkpoints};
use flapper_ppo::{IterationLog, Start};
use flapper_sim::RobotModel;
use flapper_train::run::{RunError, flight_trainer, saved_config};

use crate::config::{CRUISE_ENTRY, CruiseFlapFlight, CurriculumConfig, Gate, StageConfig};
use crate::error::CurriculumError;
use crate::figure::write_curriculum_figure;
use crate::flight_modes::{ModeFigures, flight_mode_figures, gate_asks_flight_modes, meets_flight_mode_bars};
use crate::identification::identification_fit_percent;
use crate::selection::{
    Extension, GateColumns, Selection, StageOutcome, StoppedStage, Validated, meets_flight_bars,
    stage_validation_time_s, stage_wall_time_s,
};
use crate::summary::Summary;
use crate::validation::{ValidationError, ValidationSet};

/// What the caller chose.
pub struct CurriculumRequest<'a> {
    pub dir: &'a Path,
    pub config: CurriculumConfig,
    /// Stop after this stage (all stages when `None`).
    pub until_stage: Option<usize>,
    /// The command line, recorded in `summary.json`.
    pub command: String,
    /// A policy (or checkpoint) the first stage starts from instead of new networks, with its
    /// `start_noise_std`: the curriculum then fine-tunes a controller, such as the shipped one on a robot
    /// of one's own (`None`: from scratch).
    pub init_from: Option<PathBuf>,
}

/// Progress the caller may show: a stage starting (with its budget in `iterations`: its `max_iterations`,
/// or less where the run's `max_env_steps` says so), each iteration, each validation.
pub enum Progress<'a> {
    StageStarts {
        stage: usize,
        of: usize,
        config: &'a StageConfig,
        iterations: usize,
        resumed_at: usize,
    },
    Iteration {
        stage: usize,
        log: &'a IterationLog,
    },
    Validated {
        stage: usize,
        row: &'a Validated,
        gate_met: bool,
    },
    /// A stage that spent its budget without meeting its gate, still learning, given more iterations.
    StageExtended {
        stage: usize,
        extension: &'a Extension,
    },
    StageDone {
        outcome: &'a StageOutcome,
    },
    /// An optional stage missed its gate or could not start for the budget (`missed`, the error a
    /// stopped run would end with): the run ends with the controller `kept` handed over.
    OptionalStageMissed {
        missed: &'a CurriculumError,
        kept: &'a StageOutcome,
    },
}

/// How many validations make a stage's recent trend ([`Selection::still_improving`]).
pub const TREND_WINDOW: usize = 4;

/// How many times one stage may be extended.
pub const MAX_EXTENSIONS: usize = 2;

/// Runs (or continues) the curriculum; returns the stages done.
pub fn run_curriculum(
    robot: &RobotModel,
    request: CurriculumRequest,
    progress: &mut dyn FnMut(Progress),
) -> Result<Vec<StageOutcome>, CurriculumError> {
    let dir = request.dir;
    std::fs::create_dir_all(dir).map_err(|e| CurriculumError::File { path: dir.to_owned(), message: e.to_string() })?;
    let _lock = lock(dir)?;
    let config = open_folder(dir, &request.config)?;
    let last = request.until_stage.unwrap_or(config.stages.len()).clamp(1, config.stages.len());
    let mut outcomes: Vec<StageOutcome> = Vec::new();
    for number in 1..=last {
        let previous = outcomes.last().map(|o| dir.join(&o.checkpoint)).or_else(|| request.init_from.clone());
        let spent_env_steps = outcomes.iter().map(|o| o.env_steps).sum();
        let result = run_stage(robot, &config, dir, number, previous, spent_env_steps, progress);
        if let Err(error) = &result {
            // An optional stage refines what the stages before it made: missing its gate, or left too
            // little budget to start, it ends the run with theirs. A required stage's missed gate stops it.
            let stage = &config.stages[number - 1];
            let kept = outcomes.last().filter(|_| stage.optional);
            let missed = match error {
                CurriculumError::GateMissed { stopped, .. } => Some(stopped.as_ref().clone()),
                CurriculumError::BudgetSpent { .. } if kept.is_some() => Some(never_started(stage, number, error)),
                _ => None,
            };
            if let Some(missed) = missed {
                // The summary and the figure show the stage that stopped or ended the run.
                let summary = Summary::new(&config, &request.command, &outcomes);
                let summary = if kept.is_some() { summary.optional_missed(missed) } else { summary.stopped_at(missed) };
                summary.write(&dir.join("summary.json"))?;
                write_figure(dir, &config, number)?;
                if let Some(kept) = kept {
                    progress(Progress::OptionalStageMissed { missed: error, kept });
                    break;
                }
            }
        }
        let outcome = result?;
        progress(Progress::StageDone { outcome: &outcome });
        outcomes.push(outcome);
        Summary::new(&config, &request.command, &outcomes).write(&dir.join("summary.json"))?;
        write_figure(dir, &config, number)?;
    }
    let policy = dir.join("policy.safetensors");
    if let Some(outcome) = outcomes.last() {
        if policy.exists() {
            std::fs::remove_file(&policy)
                .map_err(|e| CurriculumError::File { path: policy.clone(), message: e.to_string() })?;
        }
        checkpoint::export_policy(&dir.join(&outcome.checkpoint), &policy)?;
    }
    Ok(outcomes)
}

pub fn stage_dir(dir: &Path, number: usize) -> PathBuf {
    dir.join(format!("stage{number}"))
}

/// Saves the curriculum in a new folder, or checks a folder's saved one against it. A folder continues
/// with a changed curriculum as long as nothing it has started would train or be judged differently:
/// the same seed and budget, and every stage that has a folder here (finished or not) exactly as saved,
/// shared `[runner]` and `[ppo]` included. Later stages may change, be added or be removed; the saved
/// curriculum is then kept as `curriculum.replaced-N.toml` and the new one saved in its place.
fn open_folder(dir: &Path, config: &CurriculumConfig) -> Result<CurriculumConfig, CurriculumError> {
    let file = |path: &Path, e: &dyn std::fmt::Display| CurriculumError::File {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let saved_path = dir.join("curriculum.toml");
    if saved_path.exists() {
        let saved = CurriculumConfig::load(&saved_path).map_err(|e| file(&saved_path, &e))?;
        if saved.seed != config.seed {
            return Err(CurriculumError::OtherSettings { dir: dir.to_owned(), what: "the seed" });
        }
        if saved == *config {
            return Ok(saved);
        }
        let started = (1..=saved.stages.len()).filter(|&k| stage_dir(dir, k).exists()).max().unwrap_or(0);
        for number in 1..=started {
            if !same_stage(&saved, config, number) {
                return Err(CurriculumError::StartedStageChanged {
                    dir: dir.to_owned(),
                    stage: number,
                    name: saved.stages[number - 1].name.clone(),
                });
            }
        }
        if saved.max_env_steps != config.max_env_steps && !same_budgets(dir, &saved, config, started) {
            return Err(CurriculumError::OtherSettings {
                dir: dir.to_owned(),
                what: "max_env_steps, which would change the budget of a stage it has started,",
            });
        }
        let replaced = (1..).map(|n| dir.join(format!("curriculum.replaced-{n}.toml"))).find(|p| !p.exists());
        let replaced = replaced.expect("some number is free");
        std::fs::copy(&saved_path, &replaced).map_err(|e| file(&replaced, &e))?;
        checkpoint::write_atomically(&saved_path, config.to_toml().as_bytes())?;
        return Ok(config.clone());
    }
    if dir.read_dir().is_ok_and(|mut entries| entries.any(|e| e.is_ok_and(|e| e.file_name() != ".lock"))) {
        return Err(CurriculumError::NotACurriculum(dir.to_owned()));
    }
    checkpoint::write_atomically(&saved_path, config.to_toml().as_bytes())?;
    Ok(config.clone())
}

/// Clears what a stage interrupted before its first checkpoint left in its folder (the files a run writes
/// besides its checkpoints, [`RUN_FILES`]: its `config.toml`, the log of the iterations it trained, their
/// figure; a policy file comes only with a finished stage, which is never cleared), which no trainer can
/// resume from: the stage starts again as it first did and trains those iterations again, bit for bit. The
/// run folder's lock keeps every other curriculum out of it; checkpoints, which would hold work, are never
/// touched (with one, the stage resumes).
fn clear_start_without_checkpoint(here: &Path) -> Result<(), CurriculumError> {
    for name in RUN_FILES {
        let path = here.join(name);
        if path.exists() {
            std::fs::remove_file(&path).map_err(|e| CurriculumError::File { path, message: e.to_string() })?;
        }
    }
    Ok(())
}

/// The record of a stage the run's budget left too little to start (`why`, the error saying so).
fn never_started(stage: &StageConfig, number: usize, why: &CurriculumError) -> StoppedStage {
    StoppedStage {
        stage: number,
        name: stage.name.clone(),
        gate: describe_gate(&stage.gate),
        iterations: 0,
        env_steps: 0,
        wall_time_s: 0.0,
        best_iteration: None,
        best_validation_score: None,
        best_validation_rms_m: None,
        cpu: None,
        extensions: Vec::new(),
        stopped_because: Some(why.to_string()),
    }
}

/// `curriculum.svg` of stages 1 to `last` (those that trained: a stage the budget left too little to start
/// has no training log).
fn write_figure(dir: &Path, config: &CurriculumConfig, last: usize) -> Result<(), CurriculumError> {
    let stage_dirs: Vec<PathBuf> =
        (1..=last).map(|k| stage_dir(dir, k)).take_while(|d| d.join("training.csv").exists()).collect();
    write_curriculum_figure(&stage_dirs, config, &dir.join("curriculum.svg"))
        .map_err(|message| CurriculumError::File { path: dir.join("curriculum.svg"), message })
}

/// Whether stage `number` trains and is judged the same under both curricula (its own entry and the
/// training config the shared tables make of it). `restart_noise_std` and `optional` may differ: they say
/// only what a stage does once its budget is spent, so a stage that stopped can be given a restart (or
/// made optional) and continued in its folder.
fn same_stage(a: &CurriculumConfig, b: &CurriculumConfig, number: usize) -> bool {
    let Some(stage) = b.stages.get(number - 1) else { return false };
    stage.as_trained() == a.stages[number - 1].as_trained()
        && match (a.stage_train_config(number), b.stage_train_config(number)) {
            (Ok(x), Ok(y)) => x == y,
            _ => false,
        }
}

/// Whether the stages started in `dir` (1 to `started`, each the same stage under both curricula) trained
/// as they would have under `config`'s `max_env_steps`, given what the stages before each spent (their
/// `selected.json`): each finished stage had the same budget under both, and each extension or restart a
/// stage was given (`extensions.json`) is the one `config` gives; the last started stage may have more budget
/// under `config`, not less than it has trained. Then a budget raised (or lowered) changes nothing they
/// trained, only what is decided after (an extension or restart not yet given, later stages).
fn same_budgets(dir: &Path, saved: &CurriculumConfig, config: &CurriculumConfig, started: usize) -> bool {
    let mut spent = 0;
    for number in 1..=started {
        let here = stage_dir(dir, number);
        let (Ok(before), Ok(budget)) = (saved.stage_iterations(number, spent), config.stage_iterations(number, spent))
        else {
            return false;
        };
        let Ok(extensions) = read_extensions(&here) else { return false };
        let mut trained = budget;
        for extension in &extensions {
            let same = extension.at_iteration == trained
                && config.extension_iterations(number, spent, trained).ok() == Some(extension.added_iterations);
            if !same {
                return false;
            }
            trained += extension.added_iterations;
        }
        if number < started {
            let outcome: Result<StageOutcome, _> = flapper_files::read_json(&here.join("selected.json"));
            let Ok(outcome) = outcome else { return false };
            if before != budget {
                return false;
            }
            spent += outcome.env_steps;
        } else if saved_checkpoints(&here).last().is_some_and(|(iteration, _)| *iteration > trained) {
            return false;
        }
    }
    true
}

/// The folder's lock (`.lock`, released by the OS when the process ends).
fn lock(dir: &Path) -> Result<std::fs::File, CurriculumError> {
    match flapper_files::lock_folder(dir) {
        Ok(Some(file)) => Ok(file),
        Ok(None) => Err(CurriculumError::Busy(dir.to_owned())),
        Err(e) => Err(CurriculumError::File { path: dir.join(".lock"), message: e.to_string() }),
    }
}

/// One stage: read back if done, else train (fresh, from the previous stage, or resumed), judge, select.
/// `spent_env_steps`: what the stages before it spent, against the curriculum's `max_env_steps`.
fn run_stage(
    robot: &RobotModel,
    config: &CurriculumConfig,
    dir: &Path,
    number: usize,
    previous: Option<PathBuf>,
    spent_env_steps: u64,
    progress: &mut dyn FnMut(Progress),
) -> Result<StageOutcome, CurriculumError> {
    let here = stage_dir(dir, number);
    let outcome_path = here.join("selected.json");
    if outcome_path.exists() {
        return flapper_files::read_json(&outcome_path)
            .map_err(|message| CurriculumError::File { path: outcome_path.clone(), message });
    }
    let stage = &config.stages[number - 1];
    let mut train_config = config.stage_train_config(number).map_err(RunError::from)?;
    let iterations = config.stage_iterations(number, spent_env_steps).map_err(RunError::from)?;
    let needed = stage.least_iterations();
    if let Some(budget) = config.max_env_steps
        && iterations < needed
    {
        return Err(CurriculumError::BudgetSpent {
            stage: number,
            name: stage.name.clone(),
            budget,
            left: budget.saturating_sub(spent_env_steps),
            iterations,
            needed,
        });
    }
    let mut extensions = read_extensions(&here)?;
    let mut iterations = iterations + extensions.iter().map(|e| e.added_iterations).sum::<usize>();
    train_config.runner.iterations = iterations;
    let set = Arc::new(
        ValidationSet::new(&stage.validation, &train_config.task, robot.timestep_s(), config.validation_seed(number))?
            .price_energy(robot, stage.gate.reference_max_energy_ratio.keys())?
            .read_flap_on(reads_flap_on_validation(&stage.gate).then_some(CRUISE_ENTRY))?,
    );
    let names = set.names();
    let selection_path = here.join("selection.csv");
    let mut selection = Selection::read(&selection_path, &names, GateColumns::of(&stage.gate))?;

    let saved = saved_checkpoints(&here);
    let resumed_at = saved.last().map(|(iteration, _)| *iteration);
    // Done training: the final policy is written, or the budget is spent, or the gate was met before
    // the last checkpoint (the run stops one iteration after the validation that meets it).
    // (An extended stage wrote its policy when its first budget ran out: only its checkpoints tell.)
    let mut stopped_because = None;
    let mut finished = (here.join("policy.safetensors").exists() && extensions.is_empty())
        || resumed_at.is_some_and(|at| at >= iterations || selection.gate_met_before(&stage.gate, at));
    let mut resumed_at = resumed_at;
    // Judge what is saved but not judged (an interruption between a checkpoint and its validation);
    // rows after the last checkpoint belong to iterations the resumed run will do again.
    selection.truncate_after(resumed_at.unwrap_or(0));
    let averaged = config.averaged_checkpoints(number);
    for (iteration, path) in saved {
        if !selection.has(iteration) {
            let env_steps = checkpoint::load(&path)?.info.env_steps;
            let judged = judged_policy(&here, iteration, averaged)?;
            selection.rows.push(judge(robot, &set, &stage.gate, iteration, env_steps, &judged)?);
        }
    }
    selection.rows.sort_by_key(|r| r.iteration);
    std::fs::create_dir_all(&here).map_err(|e| CurriculumError::File { path: here.clone(), message: e.to_string() })?;
    selection.write(&selection_path, &names)?;
    if resumed_at.is_none() && !finished {
        clear_start_without_checkpoint(&here)?;
    }

    loop {
        if !finished {
            progress(Progress::StageStarts {
                stage: number,
                of: config.stages.len(),
                config: stage,
                iterations,
                resumed_at: resumed_at.unwrap_or(0),
            });
            let start = match (resumed_at, &previous) {
                (Some(at), _) => match restart_due(&extensions, at) {
                    Some((noise_std, from)) => Start::Restart {
                        noise_std,
                        learner_from: from.map(|iteration| checkpoint_path(&here, iteration)),
                    },
                    None => Start::Resume,
                },
                (None, Some(path)) => Start::InitFrom(path.clone()),
                (None, None) => Start::Fresh,
            };
            let mut run_config = if matches!(start, Start::Resume | Start::Restart { .. }) {
                saved_config(&here)?
            } else {
                train_config.clone()
            };
            run_config.runner.iterations = iterations;
            if number == 1 && matches!(start, Start::InitFrom(_)) {
                // The first stage's own noise, as a later stage's replaces its predecessor's.
                run_config.runner.init_from_noise_std = stage.start_noise_std;
            }
            let round = Round { robot, stage, number, here: &here, names: &names, set: &set, averaged };
            selection = round.train(&run_config, start, selection, progress)?;
        }
        if choose(stage, &selection).is_some() {
            break;
        }
        let (reason, restart_noise_std) = match next_round(stage, &selection, &extensions) {
            Ok(round) => round,
            Err(why) => {
                stopped_because = Some(why);
                break;
            }
        };
        let added = config.extension_iterations(number, spent_env_steps, iterations).map_err(RunError::from)?;
        if added == 0 {
            let half = stage.max_iterations / 2;
            stopped_because = Some(if half < stage.validate_every {
                format!(
                    "{reason}, but half its max_iterations ({half}) is less than one validation interval ({})",
                    stage.validate_every
                )
            } else {
                format!(
                    "{reason}, but the run's max_env_steps leaves no room for another {} iterations after the fewest the later stages need",
                    stage.validate_every
                )
            });
            break;
        }
        let restart_from_iteration = match restart_noise_std {
            Some(_) if stage.restart_from_best => selection.best().map(|best| best.iteration),
            _ => None,
        };
        let reason = match (restart_noise_std, restart_from_iteration) {
            (Some(std), Some(best)) => format!(
                "{reason}; exploration restarted from its best checkpoint, iteration {best}, with action noise {std} \
                 (the iterations go on from {iterations})"
            ),
            (Some(std), None) => format!(
                "{reason}; exploration restarted from the checkpoint of iteration {iterations} with action noise {std}"
            ),
            (None, _) => reason,
        };
        extensions.push(Extension {
            at_iteration: iterations,
            added_iterations: added,
            reason,
            restart_noise_std,
            restart_from_iteration,
        });
        write_extensions(&here, &extensions)?;
        progress(Progress::StageExtended { stage: number, extension: extensions.last().expect("just pushed") });
        iterations += added;
        resumed_at = saved_checkpoints(&here).last().map(|(iteration, _)| *iteration);
        finished = false;
    }
    select(stage, number, &here, &selection, averaged, extensions, stopped_because)
}

/// What a stage whose budget is spent without meeting its gate does next, from its trend: more iterations
/// while it still improves; one restart of its exploration once it has stalled, if its config asks for
/// restarts; else nothing, and why (`Err`).
fn next_round(
    stage: &StageConfig,
    selection: &Selection,
    extensions: &[Extension],
) -> Result<(String, Option<f32>), String> {
    if extensions.len() >= MAX_EXTENSIONS {
        return Err(format!("it had been given {MAX_EXTENSIONS} extensions or restarts already"));
    }
    let Some(trend) = selection.trend(TREND_WINDOW) else {
        return Err(format!("fewer than {} validations tell no trend", 2 * TREND_WINDOW));
    };
    let described = trend.describe(TREND_WINDOW);
    if trend.improving() {
        return Ok((described, None));
    }
    match stage.restart_noise_std {
        Some(_) if selection.most_efficient_tracking(&stage.gate).is_some() => {
            Err(format!("{described}; it tracks every reference, so its exploration is not restarted"))
        }
        None => Err(format!("{described}; the stage restarts no exploration (its restart_noise_std is not set)")),
        Some(_) if extensions.iter().any(|e| e.restart_noise_std.is_some()) => {
            Err(format!("{described}, after its exploration had been restarted once already"))
        }
        Some(std) => Ok((described, Some(std))),
    }
}

/// The action noise to restart with, and the earlier checkpoint whose learner to take (none: the
/// latest's), when the stage's latest checkpoint (`latest`, an iteration) is the one a restart began
/// from: a run interrupted before its first checkpoint after a restart restarts again.
fn restart_due(extensions: &[Extension], latest: usize) -> Option<(f32, Option<usize>)> {
    let restart = extensions.last().filter(|e| e.at_iteration == latest)?;
    restart.restart_noise_std.map(|std| (std, restart.restart_from_iteration))
}

/// One stage's training from `start` to its config's iterations, each checkpoint judged on the
/// validation set as it is saved.
struct Round<'a> {
    robot: &'a RobotModel,
    stage: &'a StageConfig,
    number: usize,
    here: &'a Path,
    names: &'a [String],
    set: &'a Arc<ValidationSet>,
    averaged: usize,
}

impl Round<'_> {
    fn train(
        &self,
        run_config: &flapper_train::config::TrainConfig,
        start: Start,
        selection: Selection,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<Selection, CurriculumError> {
        let (number, averaged) = (self.number, self.averaged);
        let mut trainer = flight_trainer(self.robot, run_config, self.here, start)?;
        let shared = Arc::new(Mutex::new((selection, Vec::<Validated>::new())));
        let hook_state = shared.clone();
        let (hook_robot, hook_names, hook_path, hook_gate, hook_set) = (
            self.robot.clone(),
            self.names.to_vec(),
            self.here.join("selection.csv"),
            self.stage.gate.clone(),
            self.set.clone(),
        );
        trainer.add_checkpoint_hook(Box::new(move |event| {
            let env_steps = event.history.last().map_or(0, |l| l.env_steps);
            let path = judged_policy(event.dir, event.iteration, averaged).map_err(|e| e.to_string())?;
            let row = judge(&hook_robot, &hook_set, &hook_gate, event.iteration, env_steps, &path)
                .map_err(|e| e.to_string())?;
            let mut state = hook_state.lock().expect("no panic while holding the selection");
            state.0.rows.retain(|r| r.iteration != row.iteration);
            state.0.rows.push(row.clone());
            state.0.write(&hook_path, &hook_names).map_err(|e| e.to_string())?;
            state.1.push(row);
            Ok(())
        }));
        let gate = self.stage.gate.clone();
        // Validations judged since the last report: after each iteration, and once more at the end for the
        // stage's last checkpoint, which is judged after its iteration has been reported.
        let report = |progress: &mut dyn FnMut(Progress)| {
            let mut state = shared.lock().expect("no panic while holding the selection");
            let fresh: Vec<Validated> = state.1.drain(..).collect();
            for row in &fresh {
                progress(Progress::Validated { stage: number, row, gate_met: state.0.gate_met(&gate) });
            }
            state.0.gate_met(&gate)
        };
        trainer.run(&mut |log, _| {
            progress(Progress::Iteration { stage: number, log });
            !report(&mut *progress)
        })?;
        report(progress);
        let state = shared.lock().expect("no panic while holding the selection");
        Ok(state.0.clone())
    }
}

/// The stage's extensions so far (`extensions.json`; none before the first).
fn read_extensions(here: &Path) -> Result<Vec<Extension>, CurriculumError> {
    let path = here.join("extensions.json");
    if !path.exists() {
        return Ok(Vec::new());
    }
    flapper_files::read_json(&path).map_err(|message| CurriculumError::File { path, message })
}

fn write_extensions(here: &Path, extensions: &[Extension]) -> Result<(), CurriculumError> {
    let path = here.join("extensions.json");
    flapper_files::write_json(&path, &extensions).map_err(|e| CurriculumError::File { path, message: e.to_string() })
}

/// The checkpoint a stage hands over, and whether it met the identification bar (where the gate has
/// one): the best that meets the gate, else, where the identification is sought but not required, the
/// best that flies every other bar.
fn choose<'a>(stage: &'a StageConfig, selection: &'a Selection) -> Option<(&'a Validated, Option<bool>)> {
    match selection.best_meeting(&stage.gate) {
        Some(best) => Some((best, stage.gate.identification_fit_percent.map(|_| true))),
        None => selection
            .best_flying(&stage.gate)
            .filter(|_| stage.gate.identification_fit_percent.is_some() && !stage.gate.identification_required)
            .map(|b| (b, Some(false))),
    }
}

/// The checkpoint a stage that will train no more hands over, and which of its sought bars it met.
struct HandOver<'a> {
    best: &'a Validated,
    /// Whether the identification was met (`None`: not asked).
    identification_met: Option<bool>,
    /// `Some(false)` where the flight modes were sought and not met (`None`: met or not asked).
    flight_modes_met: Option<bool>,
    /// `Some(false)` where the RMS bars were sought and not met (`None`: met or not asked).
    rms_met: Option<bool>,
    /// `Some(false)` where the randomized entries were sought and not met (`None`: met or not asked).
    randomized_met: Option<bool>,
}

/// What a stage that will train no more hands over: [`choose`]'s checkpoint, else, where the gate's
/// flight-mode bars are sought, the most efficient checkpoint that meets every tracking bar from the gate's
/// `min_iterations` on, else before them (a fine-tuning stage whose budget was cut short still hands over
/// a controller that tracks, if it ever had one), else, where its RMS bars are sought, the best
/// checkpoint that completes every reference ([`Selection::best_completing`]), else, where its randomized
/// entries are sought, the best one that completes every named entry ([`Selection::best_completing_named`]).
fn choose_at_the_end<'a>(stage: &'a StageConfig, selection: &'a Selection) -> Option<HandOver<'a>> {
    if let Some((best, identification_met)) = choose(stage, selection) {
        return Some(HandOver {
            best,
            identification_met,
            flight_modes_met: None,
            rms_met: None,
            randomized_met: None,
        });
    }
    let gate = &stage.gate;
    let identification_met = gate.identification_fit_percent.map(|_| false);
    let flight_modes_met = |best: &Validated| {
        (gate_asks_flight_modes(gate) && !meets_flight_mode_bars(gate, best.modes.as_ref(), &best.score))
            .then_some(false)
    };
    let tracking = selection.most_efficient_tracking(gate).or_else(|| selection.most_efficient_tracking_from(gate, 0));
    let tracking = tracking.map(|best| HandOver {
        best,
        identification_met,
        flight_modes_met: Some(false),
        rms_met: None,
        randomized_met: None,
    });
    // A checkpoint handed over with some sought bar unmet, marked so.
    let marked = |best, rms_met, randomized_met| HandOver {
        best,
        identification_met,
        flight_modes_met: flight_modes_met(best),
        rms_met,
        randomized_met,
    };
    let completing = || selection.best_completing(gate).map(|best| marked(best, Some(false), None));
    let completing_named = || {
        selection.best_completing_named(gate).map(|best| {
            marked(best, (!best.score.rms_met(gate)).then_some(false), (!best.score.completes(gate)).then_some(false))
        })
    };
    tracking.or_else(completing).or_else(completing_named)
}

/// The policy a validation of `iteration` judges: the checkpoint itself, or with `averaged` > 1 the
/// mean of the weights of the stage's last `averaged` checkpoints up to it
/// ([`crate::config::StageConfig::average_checkpoints`]), written once to `averaged/` in the stage's
/// folder (the checkpoints do not change, so a file found there is the same average).
fn judged_policy(here: &Path, iteration: usize, averaged: usize) -> Result<PathBuf, CurriculumError> {
    let path = here.join(judged_file(iteration, averaged));
    if averaged > 1 && !path.exists() {
        let saved: Vec<PathBuf> =
            saved_checkpoints(here).into_iter().filter(|(at, _)| *at <= iteration).map(|(_, path)| path).collect();
        let window = &saved[saved.len().saturating_sub(averaged)..];
        std::fs::create_dir_all(path.parent().expect("inside the stage folder"))
            .map_err(|e| CurriculumError::File { path: path.clone(), message: e.to_string() })?;
        checkpoint::export_average_policy(window, &path)?;
    }
    Ok(path)
}

/// Where the policy judged at `iteration` lives, relative to its stage's folder: the checkpoint, or
/// its average in `averaged/`.
fn judged_file(iteration: usize, averaged: usize) -> PathBuf {
    if averaged > 1 {
        PathBuf::from(format!("averaged/iter_{iteration:06}.safetensors"))
    } else {
        checkpoint_path(Path::new(""), iteration)
    }
}

/// Flies the validation set with the checkpoint at `path`, and the longitudinal reference for its flight
/// modes where the gate has a flight-mode bar; where the gate asks for identification and the checkpoint meets
/// every other bar, identifies its closed loop.
fn judge(
    robot: &RobotModel,
    set: &ValidationSet,
    gate: &Gate,
    iteration: usize,
    env_steps: u64,
    path: &Path,
) -> Result<Validated, ValidationError> {
    let began = Instant::now();
    let score = set.judge(robot, path)?;
    // The cruise reference is flown again for the frequency bar only; the validation's starts need no flight.
    let flap_flight =
        if gate.cruise_flap_hz.is_some() { gate.cruise_flap_flight } else { CruiseFlapFlight::LongitudinalSegment };
    let mut modes =
        if gate_asks_flight_modes(gate) { Some(flight_mode_figures(robot, path, flap_flight)?) } else { None };
    if let Some(figures) = modes.as_mut()
        && reads_flap_on_validation(gate)
    {
        let cruise = score.references.iter().find(|r| r.name == CRUISE_ENTRY);
        figures.cruise_flap_hz = cruise.and_then(|r| r.flap_hz).unwrap_or(f64::NAN);
    }
    let mut row = Validated { iteration, env_steps, validation_s: 0.0, score, modes, identification_fit_percent: None };
    if gate.identification_fit_percent.is_some() && meets_flight_bars(gate, &row) {
        row.identification_fit_percent = Some(identification_fit_percent(robot, path)?);
    }
    row.validation_s = began.elapsed().as_secs_f64();
    Ok(row)
}

/// Whether the gate's flap bar reads the validation's own cruise starts.
fn reads_flap_on_validation(gate: &Gate) -> bool {
    gate.cruise_flap_hz.is_some() && gate.cruise_flap_flight == CruiseFlapFlight::ValidationStarts
}

/// Picks the stage's checkpoint, or stops the run when no checkpoint met the gate. The identification
/// bar is sought, not required, unless the gate says `identification_required`
/// ([`Gate::identification_fit_percent`]): without a checkpoint that meets it, the best one that meets
/// the other bars is handed over, marked as not identified well enough.
fn select(
    stage: &StageConfig,
    number: usize,
    here: &Path,
    selection: &Selection,
    averaged: usize,
    extensions: Vec<Extension>,
    stopped_because: Option<String>,
) -> Result<StageOutcome, CurriculumError> {
    let history = flapper_ppo::training_log::read_history(&here.join("training.csv"))
        .map_err(|message| CurriculumError::File { path: here.join("training.csv"), message })?;
    let last = history.last();
    let iterations = last.map_or(0, |l| l.iteration);
    let chosen = choose_at_the_end(stage, selection);
    let env_steps = last.map_or(0, |l| l.env_steps);
    let wall_time_s = stage_wall_time_s(selection, last.map_or(0.0, |l| l.wall_time_s), iterations);
    let Some(HandOver { best, identification_met, flight_modes_met, rms_met, randomized_met }) = chosen else {
        let best = selection.best();
        let stopped = StoppedStage {
            stage: number,
            name: stage.name.clone(),
            gate: describe_gate(&stage.gate),
            iterations,
            env_steps,
            wall_time_s,
            best_iteration: best.map(|b| b.iteration),
            best_validation_score: best.map(|b| b.score.completed_percent),
            best_validation_rms_m: best.map(|b| b.score.mean_rms_m),
            cpu: crate::machine::cpu_model(),
            extensions: extensions.clone(),
            stopped_because,
        };
        return Err(CurriculumError::GateMissed {
            best: format!(
                "iteration {}, completed {:.1}% with a mean RMS error of {:.3} m{}{}{}",
                best.map_or(0, |b| b.iteration),
                best.map_or(0.0, |b| b.score.completed_percent),
                best.map_or(f64::NAN, |b| b.score.mean_rms_m),
                describe_rms_bars(&stage.gate, selection),
                describe_flight_modes(&stage.gate, selection),
                describe_identified(selection)
            ),
            dir: here.to_owned(),
            stopped: Box::new(stopped),
        });
    };
    let checkpoint = PathBuf::from(format!("stage{number}")).join(judged_file(best.iteration, averaged));
    let outcome = StageOutcome {
        stage: number,
        name: stage.name.clone(),
        iterations,
        env_steps,
        wall_time_s,
        validation_wall_time_s: Some(stage_validation_time_s(selection)),
        selected_iteration: best.iteration,
        validation_score: best.score.completed_percent,
        validation_rms_m: best.score.mean_rms_m,
        checkpoint,
        extensions,
        identification_met,
        flight_modes_met,
        rms_met,
        randomized_met,
        glide_fraction: best.modes.map(|f| f.glide_fraction),
        energy_ratio: best.modes.map(|f| f.energy_ratio),
        cruise_flap_hz: best.modes.map(|f| f.cruise_flap_hz),
        cpu: crate::machine::cpu_model(),
    };
    let selected = here.join("selected.json");
    flapper_files::write_json(&selected, &outcome)
        .map_err(|e| CurriculumError::File { path: selected.clone(), message: e.to_string() })?;
    Ok(outcome)
}

/// For each entry with its own RMS bar, the smallest error any checkpoint flew it with (from the gate's
/// `min_iterations` on), for the missed gate's message: which bar held the gate shut, and by how much.
fn describe_rms_bars(gate: &Gate, selection: &Selection) -> String {
    let closest: Vec<String> = gate
        .reference_max_rms_m
        .iter()
        .map(|(name, bar)| {
            let best = selection
                .rows
                .iter()
                .filter(|r| r.iteration >= gate.min_iterations)
                .filter_map(|r| Some((r.iteration, r.score.reference(name)?.mean_rms_m)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match best {
                Some((iteration, rms)) => format!("{name} {rms:.3} m at best (iteration {iteration}; bar {bar} m)"),
                None => format!("{name} never flown (bar {bar} m)"),
            }
        })
        .collect();
    if closest.is_empty() { String::new() } else { format!("; {}", closest.join(", ")) }
}

/// The closest any checkpoint came to each flight-mode bar (from the gate's `min_iterations` on): the
/// largest glide fraction, the smallest energy ratio, the cruise flap frequency nearest the range; for
/// the missed gate's message.
fn describe_flight_modes(gate: &Gate, selection: &Selection) -> String {
    let rows: Vec<(usize, ModeFigures)> = selection
        .rows
        .iter()
        .filter(|r| r.iteration >= gate.min_iterations)
        .filter_map(|r| Some((r.iteration, r.modes?)))
        .collect();
    let closest = |value: &dyn Fn(&ModeFigures) -> f64, distance: &dyn Fn(f64) -> f64| {
        rows.iter()
            .map(|(iteration, f)| (*iteration, value(f)))
            .filter(|(_, x)| x.is_finite())
            .min_by(|a, b| distance(a.1).total_cmp(&distance(b.1)))
    };
    let never = "no checkpoint flew the longitudinal reference to its end";
    let mut parts = Vec::new();
    if let Some(bar) = gate.glide_fraction {
        parts.push(match closest(&|f| f.glide_fraction, &|x| -x) {
            Some((at, x)) => format!("glide fraction {x:.2} at best (iteration {at}; bar {bar})"),
            None => format!("{never} for its glide (bar {bar})"),
        });
    }
    if let Some(bar) = gate.max_energy_ratio {
        parts.push(match closest(&|f| f.energy_ratio, &|x| x) {
            Some((at, x)) => format!("energy {x:.2} x the scripted gait's at best (iteration {at}; bar {bar} x)"),
            None => format!("{never} for its energy (bar {bar} x)"),
        });
    }
    if let Some([low, high]) = gate.cruise_flap_hz {
        let outside = |x: f64| (low - x).max(x - high).max(0.0);
        parts.push(match closest(&|f| f.cruise_flap_hz, &outside) {
            Some((at, x)) => format!("cruise flap {x:.2} Hz at closest (iteration {at}; bar {low}-{high} Hz)"),
            None => format!("{never} for its flap frequency (bar {low}-{high} Hz)"),
        });
    }
    parts.iter().map(|p| format!("; {p}")).collect()
}

/// The identified checkpoints of a stage in words (x, y, z fit of each), for the missed gate's message.
fn describe_identified(selection: &Selection) -> String {
    let identified: Vec<String> = selection
        .rows
        .iter()
        .filter_map(|r| {
            let [x, y, z] = r.identification_fit_percent?;
            Some(format!("{}: x {x:.1}%, y {y:.1}%, z {z:.1}%", r.iteration))
        })
        .collect();
    match (selection.columns.identification, identified.is_empty()) {
        (false, _) => String::new(),
        (true, true) => "; no checkpoint met the other bars, none was identified".to_owned(),
        (true, false) => format!("; identified (iteration: fit per axis): {}", identified.join("; ")),
    }
}

/// The gate in words, for messages.
pub fn describe_gate(gate: &Gate) -> String {
    // Each bar goes to what the gate requires, or to what it seeks: required while the budget lasts, and
    // at the budget's end the best checkpoint without it is handed over, marked so (`choose_at_the_end`).
    let mut required = vec![match gate.procedural_completed_percent {
        None => format!("every validation reference completed in at least {}% of its episodes", gate.completed_percent),
        Some(drawn) => format!(
            "every named validation reference completed in at least {}% of its episodes, the procedural ones in \
             {drawn}% of theirs together",
            gate.completed_percent
        ),
    }];
    let mut sought = Vec::new();
    if let Some(randomized) = gate.randomized_completed_percent {
        let bar = format!("each randomized entry completed in at least {randomized}% of its episodes");
        if gate.randomized_sought { sought.push(bar) } else { required.push(bar) }
    }
    let mut rms_bars = Vec::new();
    if let Some(rms) = gate.max_rms_m {
        rms_bars.push(format!("mean RMS error at most {rms} m"));
    }
    if !gate.reference_max_rms_m.is_empty() {
        let bars: Vec<String> = gate.reference_max_rms_m.iter().map(|(name, bar)| format!("{name} {bar} m")).collect();
        rms_bars.push(format!("mean RMS error of {}", bars.join(", ")));
    }
    if gate.rms_sought {
        sought.extend(rms_bars)
    } else {
        required.extend(rms_bars)
    }
    let mut flight_mode_bars = Vec::new();
    if let Some(share) = gate.glide_fraction {
        flight_mode_bars.push(format!(
            "the wings held at least {share} of the longitudinal reference's glide segment (flapper modes)"
        ));
    }
    if let Some(ratio) = gate.max_energy_ratio {
        flight_mode_bars.push(format!(
            "the energy per metre along the longitudinal reference at most {ratio} x the scripted gait's"
        ));
    }
    if !gate.reference_max_energy_ratio.is_empty() {
        let bars: Vec<String> =
            gate.reference_max_energy_ratio.iter().map(|(name, bar)| format!("{name} {bar} x")).collect();
        flight_mode_bars.push(format!(
            "the energy per metre over the validation's starts, to the scripted gait's on the same starts, of {}",
            bars.join(", ")
        ));
    }
    if let Some([low, high]) = gate.cruise_flap_hz {
        let flight = match gate.cruise_flap_flight {
            CruiseFlapFlight::LongitudinalSegment => "in its cruise segment",
            CruiseFlapFlight::CruiseReference => "along the cruise reference",
            CruiseFlapFlight::ValidationStarts => "along the cruise reference, averaged over the validation's starts,",
        };
        flight_mode_bars.push(format!("the flap's fundamental {flight} within {low}-{high} Hz"));
    }
    if gate.flight_modes_required {
        required.extend(flight_mode_bars)
    } else {
        sought.extend(flight_mode_bars)
    }
    if let Some(fit) = gate.identification_fit_percent {
        let bar = format!("every axis of the identified closed loop (flapper sysid) fitting at least {fit}%");
        if gate.identification_required { required.push(bar) } else { sought.push(bar) }
    }
    let mut text = required.join(", ");
    if !sought.is_empty() {
        text.push_str(&format!("; sought (required only while the budget lasts): {}", sought.join(", ")));
    }
    if gate.min_iterations > 0 {
        text.push_str(&format!("; from iteration {} on", gate.min_iterations));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn extension(at_iteration: usize, restart_noise_std: Option<f32>) -> Extension {
        Extension {
            at_iteration,
            added_iterations: 100,
            reason: String::new(),
            restart_noise_std,
            restart_from_iteration: None,
        }
    }

    #[test]
    fn a_restart_is_due_only_from_the_checkpoint_it_began_at() {
        let restarted = [extension(3200, None), extension(3300, Some(0.4))];
        assert_eq!(restart_due(&restarted, 3300), Some((0.4, None)), "no checkpoint since the restart: restart again");
        let from_best = [Extension { restart_from_iteration: Some(2900), ..extension(3200, Some(0.4)) }];
        assert_eq!(restart_due(&from_best, 3200), Some((0.4, Some(2900))), "again from the same best checkpoint");
        assert_eq!(restart_due(&restarted, 3350), None, "a checkpoint since: resume it");
        assert_eq!(restart_due(&restarted[..1], 3200), None, "an extension is no restart");
        assert_eq!(restart_due(&[extension(3200, Some(0.4)), extension(3300, None)], 3200), None, "an earlier one");
        assert_eq!(restart_due(&[], 3200), None);
    }

    /// A checkpoint that flew the one validation reference `completed` of 10 at `energy_ratio`, 5 Hz.
    fn judged(iteration: usize, completed: usize, energy_ratio: f64) -> Validated {
        let modes = Some(ModeFigures { glide_fraction: 0.0, energy_ratio, cruise_flap_hz: 5.0 });
        Validated { modes, ..Validated::of_cruise(iteration, completed, 0.2) }
    }

    /// The gate in words (the curriculum's stage line, `summary.json`, a stop's message) lists what it
    /// requires first and what it only seeks after, each bar once.
    #[test]
    fn the_gate_in_words_parts_the_bars_it_requires_from_those_it_seeks() {
        let sought_parts = |text: &str| {
            text.split_once("; sought (required only while the budget lasts): ")
                .map(|(required, sought)| (required.to_owned(), sought.to_owned()))
                .unwrap_or((text.to_owned(), String::new()))
        };
        // The transfer's stage 4 seeks its randomized entries, its RMS bars and its identification.
        let transfer = crate::config::shipped("curriculum-transfer.toml").stages[0].gate.clone();
        let (required, sought) = sought_parts(&describe_gate(&transfer));
        assert!(required.starts_with("every validation reference completed in at least 95%"), "{required}");
        for bar in ["each randomized entry completed in at least 95%", "mean RMS error of cruise 0.3 m", "identified"] {
            assert!(sought.contains(bar) && !required.contains(bar), "{bar} sought: {sought} | {required}");
        }
        assert!(sought.ends_with("; from iteration 300 on"), "{sought}");
        // Required instead, the same bars move to the required part.
        let strict = Gate { randomized_sought: false, rms_sought: false, identification_required: true, ..transfer };
        let (required, sought) = sought_parts(&describe_gate(&strict));
        assert!(sought.is_empty() && required.contains("randomized") && required.contains("identified"), "{required}");
        // The efficient stage seeks its flight-mode bars; required, they are listed with the tracking.
        let efficient = crate::config::shipped("curriculum.toml").stages[4].gate.clone();
        let (required, sought) = sought_parts(&describe_gate(&efficient));
        assert!(sought.contains("at most 1.2 x the scripted gait's") && sought.contains("within 4-6 Hz"), "{sought}");
        assert!(!required.contains("scripted gait"), "{required}");
        let (required, _) = sought_parts(&describe_gate(&Gate { flight_modes_required: true, ..efficient }));
        assert!(required.contains("at most 1.2 x the scripted gait's"), "{required}");
        // A gate of completion alone says so and nothing more.
        let first = crate::config::shipped("curriculum.toml").stages[0].gate.clone();
        assert_eq!(describe_gate(&first), "every validation reference completed in at least 90% of its episodes");
    }

    #[test]
    fn a_stage_seeking_flight_modes_hands_over_a_tracking_checkpoint_before_its_min_iterations_only_as_a_last_resort() {
        // The shipped efficient-flight stage's gate (1.2 x, 4-6 Hz sought from iteration 300 on), tracking
        // asked of one reference: 95% of 10 episodes.
        let mut stage = crate::config::shipped("curriculum.toml").stages[4].clone();
        stage.gate = Gate { identification_fit_percent: None, ..stage.gate.clone() };
        stage.gate.reference_max_rms_m.clear();
        let pick = |rows: Vec<Validated>| {
            let selection = Selection { rows, columns: Default::default() };
            choose_at_the_end(&stage, &selection).map(|h| (h.best.iteration, h.identification_met, h.flight_modes_met))
        };
        // Seed 3's stage 5 cut to 400 iterations: tracking at 150 (2.17 x), at none from 300 on.
        let cut_short = vec![judged(150, 10, 2.17), judged(300, 9, 2.16), judged(350, 9, 2.15), judged(400, 9, 2.2)];
        assert_eq!(pick(cut_short), Some((150, None, Some(false))));
        // A tracking checkpoint from 300 on is preferred to a more efficient one before.
        assert_eq!(pick(vec![judged(150, 10, 1.3), judged(300, 10, 1.9)]), Some((300, None, Some(false))));
        // One that meets the energy bar from 300 on meets the gate.
        assert_eq!(pick(vec![judged(150, 10, 1.1), judged(300, 10, 1.15)]), Some((300, None, None)));
        // Nothing tracks: nothing handed over, the run stops.
        assert_eq!(pick(vec![judged(150, 9, 1.1), judged(300, 8, 1.15)]), None);
    }

    #[test]
    fn the_shipped_stage_4_hands_over_a_completing_checkpoint_that_misses_its_rms_bars_marked_so() {
        // Stage 4's gate with one reference, cruise at 0.3 m, and its identification sought.
        let shipped = crate::config::shipped("curriculum.toml").stages[3].clone();
        let gate = Gate { reference_max_rms_m: [("cruise".to_owned(), 0.3)].into(), ..shipped.gate.clone() };
        let stage = StageConfig { gate, ..shipped };
        let pick_with = |stage: &StageConfig, rows: Vec<Validated>| {
            let selection = Selection { rows, columns: Default::default() };
            choose_at_the_end(stage, &selection).map(|h| (h.best.iteration, h.identification_met, h.rms_met))
        };
        let pick = |rows: Vec<Validated>| pick_with(&stage, rows);
        let fits = |row: Validated, fit: f64| Validated { identification_fit_percent: Some([fit; 3]), ..row };
        let within = fits(Validated::of_cruise(400, 10, 0.25), 85.0);
        let looser = [Validated::of_cruise(300, 10, 0.36), Validated::of_cruise(500, 10, 0.33)];
        // Within the bar and identified: the gate is met.
        assert_eq!(pick(vec![looser[0].clone(), within.clone()]), Some((400, Some(true), None)));
        // Within the bar, not identified: the identification's own fallback.
        let unidentified = fits(within, 60.0);
        assert_eq!(pick(vec![looser[0].clone(), unidentified]), Some((400, Some(false), None)));
        // Never within 0.3 m: the best completing checkpoint (the least error), marked.
        assert_eq!(pick(looser.to_vec()), Some((500, Some(false), Some(false))));
        // Before min_iterations (300) or completing too little: nothing, the run stops.
        assert_eq!(pick(vec![Validated::of_cruise(200, 10, 0.36), Validated::of_cruise(400, 9, 0.33)]), None);
        // Required again, the same looser checkpoints stop the run.
        let required = StageConfig { gate: Gate { rms_sought: false, ..stage.gate.clone() }, ..stage.clone() };
        assert_eq!(pick_with(&required, looser.to_vec()), None);
    }

    /// The transfer's stage 4 seeks its randomized entries: a budget spent without them hands over the best
    /// checkpoint that completes every named entry, marked `randomized_met: false`; the shipped stage 4,
    /// which requires them, stops instead. Completing a named entry too little still stops both.
    #[test]
    fn the_transfer_s_stage_4_hands_over_a_checkpoint_missing_a_randomized_entry_marked_so() {
        use crate::validation::{ReferenceScore, Score};
        let with_cruise_rms = |stage: StageConfig| {
            let gate = Gate { reference_max_rms_m: [("cruise".to_owned(), 0.3)].into(), ..stage.gate.clone() };
            StageConfig { gate, ..stage }
        };
        let shipped = with_cruise_rms(crate::config::shipped("curriculum.toml").stages[3].clone());
        let transfer = with_cruise_rms(crate::config::shipped("curriculum-transfer.toml").stages[0].clone());
        assert!(transfer.gate.randomized_sought && !shipped.gate.randomized_sought);
        // Cruise `completed` of 10 at `rms`, longitudinal under the fluid coefficients `fluid` of 100.
        let row = |iteration: usize, completed: usize, rms: f64, fluid: usize| {
            let references = vec![
                ReferenceScore::flown("cruise", completed, 10, rms),
                ReferenceScore::flown("longitudinal~fluid", fluid, 100, 0.3),
            ];
            let completed_percent = 100.0 * (completed + fluid) as f64 / 110.0;
            let score = Score { completed_percent, mean_rms_m: rms, references };
            Validated { score, identification_fit_percent: Some([85.0; 3]), ..Validated::of_cruise(iteration, 0, 0.0) }
        };
        let pick = |stage: &StageConfig, rows: Vec<Validated>| {
            let selection = Selection { rows, columns: Default::default() };
            choose_at_the_end(stage, &selection)
                .map(|h| (h.best.iteration, h.identification_met, h.rms_met, h.randomized_met))
        };
        // Every bar at 400: the gate, for both.
        let met = vec![row(300, 10, 0.25, 90), row(400, 10, 0.25, 96)];
        assert_eq!(pick(&shipped, met.clone()), Some((400, Some(true), None, None)));
        assert_eq!(pick(&transfer, met), Some((400, Some(true), None, None)));
        // The fluid entry short at every checkpoint: the transfer hands over the best that completes every
        // named entry (the most episodes completed, randomized ones included, then the least error), marked.
        let short = vec![row(300, 10, 0.28, 90), row(400, 10, 0.25, 93), row(500, 10, 0.27, 94), row(600, 9, 0.2, 94)];
        assert_eq!(pick(&shipped, short.clone()), None);
        assert_eq!(pick(&transfer, short), Some((500, Some(false), None, Some(false))));
        // Short there and over the (sought) RMS bar as well: both marked.
        let loose = vec![row(300, 10, 0.36, 90), row(400, 10, 0.33, 93)];
        assert_eq!(pick(&transfer, loose), Some((400, Some(false), Some(false), Some(false))));
        // A named entry short, or only before the gate's min_iterations: nothing, the run stops.
        assert_eq!(pick(&transfer, vec![row(200, 10, 0.25, 90), row(400, 9, 0.25, 93)]), None);
    }
}
