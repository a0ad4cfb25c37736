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
