//! The progress of long commands: a bar on a terminal, a line per finished step in a log.

use std::io::IsTerminal;

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// A progress display for `total` steps named `unit` (e.g. "settings").
pub struct Progress {
    bar: ProgressBar,
    interactive: bool,
}

impl Progress {
    pub fn new(total: usize, unit: &str) -> Self {
        let bar = ProgressBar::new(total as u64);
        let template = format!("{{bar:30}} {{pos}}/{{len}} {unit}  {{elapsed_precise}} ETA {{eta_precise}}  {{msg}}");
        bar.set_style(ProgressStyle::with_template(&template).expect("a valid template"));
        let interactive = std::io::stderr().is_terminal();
        if !interactive {
            bar.set_draw_target(ProgressDrawTarget::hidden());
        }
        Self { bar, interactive }
    }

    /// One step done: the bar moves, or a log gets a line.
    pub fn step_done(&self, what: &str) {
        self.bar.set_message(what.to_owned());
        self.bar.inc(1);
        if !self.interactive {
            eprintln!(
                "{}/{} ({:.0} s): {what}",
                self.bar.position(),
                self.bar.length().unwrap_or(0),
                self.bar.elapsed().as_secs_f64()
            );
        }
    }

    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// A mean over the episodes that ended, for a progress line: "-" when none ended (the mean is NaN then,
/// which a reader may take for a fault).
pub fn episode_mean(value: f64, decimals: usize) -> String {
    if value.is_nan() { "- (no episode ended)".to_owned() } else { format!("{value:.decimals$}") }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_mean_over_no_episodes_reads_as_none_ended() {
        assert_eq!(super::episode_mean(f64::NAN, 1), "- (no episode ended)");
        assert_eq!(super::episode_mean(183.46, 1), "183.5");
        assert_eq!(super::episode_mean(183.46, 0), "183");
    }
}
