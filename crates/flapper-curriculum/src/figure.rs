//! `curriculum.svg`: every stage in one figure against the curriculum's environment steps: the training
//! return, the validation completion and RMS error of each judged checkpoint, and the learning dynamics
//! (action noise, KL, learning rate), one colour per stage.

use std::path::{Path, PathBuf};

use flapper_plot::{COLORS, Curve, Panel, draw};
use flapper_ppo::IterationLog;
use flapper_ppo::training_log::read_history;

use crate::config::CurriculumConfig;
use crate::selection::{GateColumns, Selection};

/// Draws the stages in `stage_dirs` (stage 1 first) into `path`.
pub fn write_curriculum_figure(stage_dirs: &[PathBuf], config: &CurriculumConfig, path: &Path) -> Result<(), String> {
    let mut panels: Vec<Vec<Curve>> = (0..6).map(|_| Vec::new()).collect();
    let mut offset_m = 0.0;
    for (k, dir) in stage_dirs.iter().enumerate() {
        let history = read_history(&dir.join("training.csv"))?;
        let label = format!("stage {} ({})", k + 1, config.stages[k].name);
        let color = COLORS[k % COLORS.len()];
        let series = |f: &dyn Fn(&IterationLog) -> f64| -> Vec<(f64, f64)> {
            history.iter().map(|r| (offset_m + r.env_steps as f64 / 1e6, f(r))).filter(|(_, y)| y.is_finite()).collect()
        };
        let curve = |points| Curve { label: label.clone(), points, color, dashed: false };
        panels[0].push(curve(smoothed(&history, offset_m)));
        panels[3].push(curve(series(&|r| r.update.action_std)));
        panels[4].push(curve(series(&|r| r.update.kl)));
        panels[5].push(curve(series(&|r| r.update.learning_rate)));
        let names = selection_names(dir)?;
        let columns = GateColumns::of(&config.stages[k].gate);
        let selection = Selection::read(&dir.join("selection.csv"), &names, columns).map_err(|e| e.to_string())?;
        let at = |f: &dyn Fn(&crate::selection::Validated) -> f64| -> Vec<(f64, f64)> {
            selection.rows.iter().map(|r| (offset_m + r.env_steps as f64 / 1e6, f(r))).collect()
        };
        panels[1].push(curve(at(&|r| r.score.completed_percent)));
        panels[2].push(curve(at(&|r| r.score.mean_rms_m)));
        offset_m += history.last().map_or(0.0, |r| r.env_steps as f64 / 1e6);
    }
    let titles = [
        ("training return (mean over the episodes ended, smoothed)", "return"),
        ("validation: episodes completed", "percent"),
        ("validation: mean RMS tracking error", "m"),
        ("action noise", "mean std"),
        ("KL per update", "KL"),
        ("learning rate", "Adam step size"),
    ];
    let panels: Vec<Panel> = titles
        .iter()
        .zip(panels)
        .map(|((title, y_label), curves)| Panel {
            title: title.to_string(),
            x_label: "environment steps of the curriculum (millions)",
            y_label,
            curves,
            equal_aspect: false,
        })
        .collect();
    draw(path, (1400, 1100), &panels, (3, 2))
}

/// The reference names of a stage's selection table, from its header.
fn selection_names(dir: &Path) -> Result<Vec<String>, String> {
    let path = dir.join("selection.csv");
    let mut reader = csv::Reader::from_path(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let headers = reader.headers().map_err(|e| e.to_string())?;
    Ok(headers.iter().filter_map(|h| h.strip_suffix("_completed")).map(String::from).collect())
}

/// Return over windows of 20 iterations, weighted by the episodes that ended (few end per iteration).
fn smoothed(history: &[IterationLog], offset_m: f64) -> Vec<(f64, f64)> {
    history
        .chunks(20)
        .filter_map(|window| {
            let episodes: usize = window.iter().filter(|r| r.mean_return.is_finite()).map(|r| r.episodes).sum();
            let sum: f64 =
                window.iter().filter(|r| r.mean_return.is_finite()).map(|r| r.mean_return * r.episodes as f64).sum();
            let last = window.last()?;
            (episodes > 0).then(|| (offset_m + last.env_steps as f64 / 1e6, sum / episodes as f64))
        })
        .collect()
}
