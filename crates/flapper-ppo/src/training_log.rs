//! The training log, `training.csv`: one row per iteration, written by the runner (header, strict
//! resume, append) and read back (for learning curves over resumed runs).

use std::path::Path;

use crate::checkpoint;
use crate::ppo::UpdateStats;
use crate::runner::{IterationLog, TrainError};

/// The CSV header: fixed columns, one `end_<reason>` per episode end, the environment's diagnostics,
/// the update's statistics and the timings.
pub(crate) fn header(end_reasons: &[&str], diagnostic_names: &[String]) -> Vec<String> {
    let mut h: Vec<String> = [
        "iteration", "env_steps", "wall_time_s", "steps_per_s", "episodes", "mean_return", "mean_length",
    ]
    .map(String::from)
    .to_vec();
    h.extend(end_reasons.iter().map(|r| format!("end_{r}")));
    h.push("mean_reward".into());
    h.extend(diagnostic_names.iter().cloned());
    h.extend(
        [
            "surrogate_loss", "value_loss", "entropy", "kl", "clip_fraction", "grad_norm", "learning_rate", "action_std",
            "env_time_s", "inference_time_s", "update_time_s",
        ]
        .map(String::from),
    );
    h
}

/// A fresh run writes the header; a resumed one keeps the rows up to its checkpoint's `iteration` (a
/// killed run may have logged iterations past its last checkpoint, which the resumed run repeats).
pub(crate) fn prepare(path: &Path, header: &[String], resume: bool, iteration: usize) -> Result<(), TrainError> {
    let path = path.to_owned();
    let header = header.join(",");
    let mut text = header.clone() + "\n";
    if resume && path.exists() {
        // Read strictly: a damaged log is refused, never silently shortened.
        let damaged = |problem: String| TrainError::DamagedLog { path: path.clone(), problem };
        let bytes = std::fs::read(&path).map_err(|e| damaged(format!("cannot be read ({e})")))?;
        let existing = String::from_utf8(bytes)
            .map_err(|e| damaged(format!("is not text (invalid UTF-8 at byte {})", e.utf8_error().valid_up_to())))?;
        for (number, line) in existing.lines().enumerate().skip(1) {
            let Some(row_iteration) = line.split(',').next().and_then(|v| v.parse::<usize>().ok()) else {
                return Err(damaged(format!("line {} does not start with an iteration number", number + 1)));
            };
            if row_iteration <= iteration {
                text.push_str(line);
                text.push('\n');
            }
        }
    }
    checkpoint::write_atomically(&path, text.as_bytes())?;
    Ok(())
}

/// Appends one iteration's row (a crash loses at most this row, which `prepare` then refuses).
pub(crate) fn append(path: &Path, log: &IterationLog) -> Result<(), TrainError> {
    use std::io::Write;
    let path = path.to_owned();
    let u = &log.update;
    let mut fields: Vec<String> = vec![
        log.iteration.to_string(),
        log.env_steps.to_string(),
        format!("{:.3}", log.wall_time_s),
        format!("{:.1}", log.steps_per_s),
        log.episodes.to_string(),
        format!("{:.6}", log.mean_return),
        format!("{:.3}", log.mean_length),
    ];
    fields.extend(log.end_counts.iter().map(|c| c.to_string()));
    fields.push(format!("{:.6}", log.mean_reward));
    fields.extend(log.diagnostics.iter().map(|d| format!("{d:.6}")));
    for v in [u.surrogate_loss, u.value_loss, u.entropy, u.kl, u.clip_fraction, u.grad_norm, u.learning_rate, u.action_std] {
        fields.push(format!("{v:.9}"));
    }
    for v in [log.env_time_s, log.inference_time_s, log.update_time_s] {
        fields.push(format!("{v:.4}"));
    }
    let mut file = std::fs::OpenOptions::new()
        .append(true)
        .open(&path)
        .map_err(|e| TrainError::Output { path: path.clone(), message: e.to_string() })?;
    writeln!(file, "{}", fields.join(",")).map_err(|e| TrainError::Output { path, message: e.to_string() })
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
        let get = |name: &str| column(name).and_then(|i| record.get(i)).and_then(|v| v.parse::<f64>().ok()).unwrap_or(f64::NAN);
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
            },
            env_time_s: get("env_time_s"),
            inference_time_s: get("inference_time_s"),
            update_time_s: get("update_time_s"),
        });
    }
    Ok(rows)
}
