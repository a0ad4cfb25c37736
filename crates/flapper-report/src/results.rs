//! The report folder's result files read back as the types that wrote them: what the page and the
//! paper-vs-flapper table show. A part left out of the run (or a file that does not parse) reads as
//! `None`; the page prints "-" for what depends on it and the table "not measured".

use std::collections::BTreeMap;
use std::path::Path;

use flapper_analysis::frontier::FrontierRow;
use flapper_analysis::frontier::file::read_frontier_csv;
use flapper_analysis::modes::ModesReport;
use flapper_analysis::phase::PhaseReport;
use flapper_analysis::robustness::RobustnessReport;
use flapper_analysis::sysid::SysidReport;
use flapper_eval::tracking_report::TrackingSummary;

use crate::experiments::{TRACKED_REFERENCES, TrackingFile};
use crate::tables::{ModelTables, TrainingTable};

/// The references whose robustness the report sweeps (the paper's Figs. 8 and 9); the first also
/// measures the level-flight envelope.
pub const ROBUSTNESS_REFERENCES: [&str; 2] = ["longitudinal", "lateral"];

/// Where each result lies in the report folder.
pub mod files {
    pub const SYSID: &str = "sysid/sysid.json";
    pub const PHASE: &str = "phase/phase.json";
    pub const MODES: &str = "modes/modes.json";
    pub const TABLES: &str = "tables/tables.json";
    pub const TRAINING: &str = "training/training.json";
    /// The energy frontier's rows (`flapper frontier`'s frontier.csv).
    pub const FRONTIER: &str = "frontier/frontier.csv";

    /// `flapper eval`'s figures on one named reference.
    pub fn tracking(reference: &str) -> String {
        format!("tracking/{reference}/summary.json")
    }

    pub fn robustness(reference: &str) -> String {
        format!("robustness/{reference}/robustness.json")
    }
}

/// Everything a report run measured.
#[derive(Debug, Clone, Default)]
pub struct RunResults {
    pub tracking: BTreeMap<String, TrackingFile>,
    pub sysid: Option<SysidReport>,
    pub phase: Option<PhaseReport>,
    pub modes: Option<ModesReport>,
    pub robustness: BTreeMap<String, RobustnessReport>,
    pub tables: Option<ModelTables>,
    pub training: Option<TrainingTable>,
    pub frontier: Option<Vec<FrontierRow>>,
}

impl RunResults {
    /// Reads every result file of the report folder `out`.
    pub fn read(out: &Path) -> Self {
        Self {
            tracking: TRACKED_REFERENCES
                .iter()
                .filter_map(|&name| Some((name.to_owned(), read(out, &files::tracking(name))?)))
                .collect(),
            sysid: read(out, files::SYSID),
            phase: read(out, files::PHASE),
            modes: read(out, files::MODES),
            robustness: ROBUSTNESS_REFERENCES
                .iter()
                .filter_map(|&name| Some((name.to_owned(), read(out, &files::robustness(name))?)))
                .collect(),
            tables: read(out, files::TABLES),
            training: read(out, files::TRAINING),
            frontier: read_frontier_csv(&out.join(files::FRONTIER)).ok(),
        }
    }

    /// The tracking figures on the named reference.
    pub fn tracking(&self, reference: &str) -> Option<&TrackingSummary> {
        self.tracking.get(reference).map(|file| &file.summary)
    }

    pub fn robustness(&self, reference: &str) -> Option<&RobustnessReport> {
        self.robustness.get(reference)
    }
}

/// One result file of the report folder `out`, or `None` when it is missing or does not parse.
fn read<T: serde::de::DeserializeOwned>(out: &Path, file: &str) -> Option<T> {
    flapper_files::read_json(&out.join(file)).ok()
}
