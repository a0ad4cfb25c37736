//! Learning curves of a run as one SVG (`learning_curves.svg`): return, episode length, how episodes
//! end, losses, KL and learning rate, action noise, throughput, each against environment steps. Drawn
//! after every checkpoint through the runner's checkpoint hook, from the whole `training.csv` (so a
//! resumed run's curves cover every session).

use std::path::Path;

use flapper_plot::{COLORS, Curve, Panel, draw};
use flapper_ppo::training_log::read_history;
use flapper_ppo::{CheckpointEvent, CheckpointHook, IterationLog};

/// The hook that redraws `DIR/learning_curves.svg` after each checkpoint.
pub fn learning_curves_hook() -> CheckpointHook {
    Box::new(|event: &CheckpointEvent| {
        let rows = read_history(&event.dir.join("training.csv")).unwrap_or_else(|_| event.history.to_vec());
        write_learning_curves(&rows, event.end_reasons, &event.dir.join("learning_curves.svg"))
    })
}

/// Writes the curves of `rows` to `path`; `end_reasons` name the columns of `end_counts`.
pub fn write_learning_curves(rows: &[IterationLog], end_reasons: &[&str], path: &Path) -> Result<(), String> {
    let series = |f: &dyn Fn(&IterationLog) -> f64| -> Vec<(f64, f64)> {
        rows.iter().map(|r| (r.env_steps as f64 / 1e6, f(r))).filter(|(_, y)| y.is_finite()).collect()
    };
    let curve = |label: &str, points, k: usize| Curve {
        label: label.to_owned(),
        points,
        color: COLORS[k % COLORS.len()],
        dashed: false,
    };
    let panel = |title: &str, y_label, curves| Panel {
        title: title.to_owned(),
        x_label: "environment steps (millions)",
        y_label,
        curves,
        equal_aspect: false,
    };
    let ends = end_reasons
        .iter()
        .enumerate()
        .map(|(k, reason)| {
            let fraction = |r: &IterationLog| {
                let total: usize = r.end_counts.iter().sum();
                if total == 0 { f64::NAN } else { r.end_counts.get(k).copied().unwrap_or(0) as f64 / total as f64 }
            };
            curve(reason, series(&fraction), k)
        })
        .collect();
    let panels = [
        panel("mean episode return", "return", vec![curve("return", series(&|r| r.mean_return), 0)]),
        panel("mean episode length", "steps", vec![curve("length", series(&|r| r.mean_length), 0)]),
        panel("how episodes end", "fraction of episodes", ends),
        panel(
            "losses",
            "loss",
            vec![
                curve("value", series(&|r| r.update.value_loss), 0),
                curve("surrogate", series(&|r| r.update.surrogate_loss), 1),
            ],
        ),
        panel(
            "KL and learning rate (x 10)",
            "",
            vec![
                curve("KL", series(&|r| r.update.kl), 0),
                curve("learning rate x 10", series(&|r| 10.0 * r.update.learning_rate), 1),
            ],
        ),
        panel("action noise", "mean std", vec![curve("std", series(&|r| r.update.action_std), 0)]),
        panel("mean reward per step", "reward", vec![curve("reward", series(&|r| r.mean_reward), 0)]),
        panel("throughput", "environment steps / s", vec![curve("steps/s", series(&|r| r.steps_per_s), 0)]),
    ];
    draw(path, (1400, 1300), &panels, (4, 2))
}
