//! The training log, `training.csv`: one row per iteration, written by the runner (header, strict
//! resume, append) and read back (for learning curves over resumed runs).

use std::path::Path;

use flapper_files::decimals::{each_fixed, fixed};

use crate::checkpoint;
use crate::ppo::UpdateStats;
use crate::train_error::TrainError;

/// One iteration's figures: one CSV row.
#[derive(Debug, Clone, PartialEq)]
pub struct IterationLog {
    /// Iterations completed (1 after the first).
    pub iteration: usize,
    pub env_steps: u64,
    pub wall_time_s: f64,
    /// Environment steps per second over this iteration.
    pub steps_per_s: f64,
    /// Episodes finished in this iteration, their mean return and length, and how they ended
    /// (counts in the order of the environment's `EndReason::ALL`).
    pub episodes: usize,
    pub mean_return: f64,
    pub mean_length: f64,
    pub end_counts: Vec<usize>,
    /// Mean reward per step and mean of each environment diagnostic over the rollout.
    pub mean_reward: f64,
    pub diagnostics: Vec<f64>,
    pub update: UpdateStats,
    pub env_time_s: f64,
    pub inference_time_s: f64,
    pub update_time_s: f64,
}

/// The CSV header: fixed columns, one `end_<reason>` per episode end, the environment's diagnostics,
/// the update's statistics (with `smoothness` and `curvature` after them when the run weighs them, so
/// that the logs of runs without them keep their columns) and the timings.
pub(crate) fn header(
    end_reasons: &[&str],
    diagnostic_names: &[String],
    smoothness: bool,
    curvature: bool,
) -> Vec<String> {
    let mut h: Vec<String> =
        ["iteration", "env_steps", "wall_time_s", "steps_per_s", "episodes", "mean_return", "mean_length"]
            .map(String::from)
            .to_vec();
    h.extend(end_reasons.iter().map(|r| format!("end_{r}")));
    h.push("mean_reward".into());
    h.extend(diagnostic_names.iter().cloned());
    h.extend(
        ["surrogate_loss", "value_loss", "entropy", "kl", "clip_fraction", "grad_norm", "learning_rate", "action_std"]
            .map(String::from),
    );
    if smoothness {
        h.push("smoothness".into());
    }
    if curvature {
        h.push("curvature".into());
    }
    h.extend(["env_time_s", "inference_time_s", "update_time_s"].map(String::from));
    h
}

/// One row of `training.csv`, in `header`'s column order, each number at the precision it is logged
/// with.
#[derive(serde::Serialize)]
struct TrainingRow<'a> {
    iteration: usize,
    env_steps: u64,
    #[serde(serialize_with = "fixed::<3, _>")]
    wall_time_s: f64,
    #[serde(serialize_with = "fixed::<1, _>")]
    steps_per_s: f64,
    episodes: usize,
    #[serde(serialize_with = "fixed::<6, _>")]
    mean_return: f64,
    #[serde(serialize_with = "fixed::<3, _>")]
    mean_length: f64,
    end_counts: &'a [usize],
    #[serde(serialize_with = "fixed::<6, _>")]
    mean_reward: f64,
    #[serde(serialize_with = "each_fixed::<6, _>")]
    diagnostics: &'a [f64],
    /// surrogate loss, value loss, entropy, KL, clip fraction, gradient norm, learning rate, action std
    /// and, when weighed, smoothness and curvature.
    #[serde(serialize_with = "each_fixed::<9, _>")]
    update: Vec<f64>,
    /// environments, inference, update.
    #[serde(serialize_with = "each_fixed::<4, _>")]
    times_s: [f64; 3],
}

impl<'a> TrainingRow<'a> {
    fn of(log: &'a IterationLog) -> Self {
        let u = &log.update;
        Self {
            iteration: log.iteration,
            env_steps: log.env_steps,
            wall_time_s: log.wall_time_s,
            steps_per_s: log.steps_per_s,
            episodes: log.episodes,
            mean_return: log.mean_return,
            mean_length: log.mean_length,
            end_counts: &log.end_counts,
            mean_reward: log.mean_reward,
            diagnostics: &log.diagnostics,
            update: [
                u.surrogate_loss,
                u.value_loss,
                u.entropy,
                u.kl,
                u.clip_fraction,
                u.grad_norm,
                u.learning_rate,
                u.action_std,
            ]
            .into_iter()
            .chain(u.smoothness)
            .chain(u.curvature)
            .collect(),
            times_s: [log.env_time_s, log.inference_time_s, log.update_time_s],
        }
    }
}

/// The rows' writer: no header of its own (the columns depend on the environment; `header` names them).
fn writer<W: std::io::Write>(sink: W) -> csv::Writer<W> {
    csv::WriterBuilder::new().has_headers(false).from_writer(sink)
}

/// A fresh run writes the header; a resumed one keeps the rows up to its checkpoint's `iteration` (a
/// killed run may have logged iterations past its last checkpoint, which the resumed run repeats).
pub(crate) fn prepare(path: &Path, header: &[String], resume: bool, iteration: usize) -> Result<(), TrainError> {
    let path = path.to_owned();
    let mut kept = writer(Vec::new());
    let output = |e: csv::Error| TrainError::Output { path: path.clone(), message: e.to_string() };
    kept.write_record(header).map_err(output)?;
    if resume && path.exists() {
        // Read strictly: a damaged log is refused, never silently shortened.
        let damaged = |problem: String| TrainError::DamagedLog { path: path.clone(), problem };
        let bytes = std::fs::read(&path).map_err(|e| damaged(format!("cannot be read ({e})")))?;
        if let Err(e) = std::str::from_utf8(&bytes) {
            return Err(damaged(format!("is not text (invalid UTF-8 at byte {})", e.valid_up_to())));
        }
        let mut reader = csv::ReaderBuilder::new().flexible(true).from_reader(bytes.as_slice());
        for record in reader.records() {
            let record = record.map_err(|e| damaged(format!("cannot be read as CSV ({e})")))?;
            let line = record.position().map_or(0, |p| p.line());
            let Some(row_iteration) = record.get(0).and_then(|v| v.parse::<usize>().ok()) else {
                return Err(damaged(format!("line {line} does not start with an iteration number")));
            };
            // Rows past the checkpoint are dropped whole, a row cut short by a crash among them.
            if row_iteration <= iteration {
                if record.len() != header.len() {
                    return Err(damaged(format!(
                        "line {line} has {} fields, the header {}",
                        record.len(),
                        header.len()
                    )));
                }
                kept.write_record(&record).map_err(output)?;
            }
        }
    }
    let text = kept.into_inner().map_err(|e| TrainError::Output { path: path.clone(), message: e.to_string() })?;
    checkpoint::write_atomically(&path, &text)?;
    Ok(())
}

/// Appends one iteration's row (a crash loses at most this row, which `prepare` then refuses).
pub(crate) fn append(path: &Path, log: &IterationLog) -> Result<(), TrainError> {
    let output = |message: String| TrainError::Output { path: path.to_owned(), message };
    let file = std::fs::OpenOptions::new().append(true).open(path).map_err(|e| output(e.to_string()))?;
    let mut rows = writer(file);
    rows.serialize(TrainingRow::of(log)).map_err(|e| output(e.to_string()))?;
    rows.flush().map_err(|e| output(e.to_string()))
}

/// Reads the plotted columns of a training CSV back (for learning curves over resumed runs).
pub fn read_history(path: &Path) -> Result<Vec<IterationLog>, String> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| e.to_string())?;
    let headers = reader.headers().map_err(|e| e.to_string())?.clone();
    let column = |name: &str| headers.iter().position(|h| h == name);
    let ends: Vec<usize> = headers.iter().enumerate().filter(|(_, h)| h.starts_with("end_")).map(|(i, _)| i).collect();
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| e.to_string())?;
        let get = |name: &str| {
            column(name).and_then(|i| record.get(i)).and_then(|v| v.parse::<f64>().ok()).unwrap_or(f64::NAN)
        };
        rows.push(IterationLog {
            iteration: get("iteration") as usize,
            env_steps: get("env_steps") as u64,
            wall_time_s: get("wall_time_s"),
            steps_per_s: get("steps_per_s"),
            episodes: get("episodes") as usize,
            mean_return: get("mean_return"),
            mean_length: get("mean_length"),
            end_counts: ends.iter().map(|&i| record.get(i).and_then(|v| v.parse().ok()).unwrap_or(0)).collect(),
            mean_reward: get("mean_reward"),
            diagnostics: Vec::new(),
            update: UpdateStats {
                surrogate_loss: get("surrogate_loss"),
                value_loss: get("value_loss"),
                entropy: get("entropy"),
                kl: get("kl"),
                clip_fraction: get("clip_fraction"),
                grad_norm: get("grad_norm"),
                learning_rate: get("learning_rate"),
                action_std: get("action_std"),
                smoothness: column("smoothness").map(|_| get("smoothness")),
                curvature: column("curvature").map(|_| get("curvature")),
            },
            env_time_s: get("env_time_s"),
            inference_time_s: get("inference_time_s"),
            update_time_s: get("update_time_s"),
        });
    }
    Ok(rows)
}
