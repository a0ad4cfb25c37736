//! A stage's selection table (`selection.csv`): one row per validated checkpoint, kept in memory and
//! rewritten whole after each validation, and the choice of the checkpoint the stage hands over.

use std::path::{Path, PathBuf};

use flapper_analysis::sysid::AXES;
use serde::{Deserialize, Serialize};

use crate::config::Gate;
use crate::flight_modes::{ModeFigures, flight_mode_bars_met, gate_asks_flight_modes, meets_flight_mode_bars};
use crate::identification::meets_identification_bar;
use crate::validation::{ReferenceScore, Score};

/// One validated checkpoint.
#[derive(Debug, Clone, PartialEq)]
pub struct Validated {
    pub iteration: usize,
    pub env_steps: u64,
    /// Seconds spent judging it: flying the validation set, and identifying it where asked.
    pub validation_s: f64,
    pub score: Score,
    /// The flight along the longitudinal reference: glide, energy and flap frequency
    /// ([`crate::flight_modes`]): `None` where the gate has no flight-mode bar, NaN where the flight failed.
    pub modes: Option<ModeFigures>,
    /// Per axis x, y, z, the fit (percent) of its identified closed loop
    /// ([`crate::identification`]): `None` where not identified (the gate asks for no identification,
    /// or the checkpoint missed the gate's other bars), NaN where it could not be identified.
    pub identification_fit_percent: Option<[f64; 3]>,
}

/// The table's file, row by row: fixed columns, then completion and RMS per reference.
#[derive(Debug, thiserror::Error)]
pub enum SelectionError {
    #[error("selection table '{path}': {message}")]
    File { path: PathBuf, message: String },
}

#[derive(Debug, Clone, Default)]
pub struct Selection {
    pub rows: Vec<Validated>,
    pub columns: GateColumns,
}

/// The columns a table has beyond the validation set's, from its stage's gate.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GateColumns {
    /// `glide_fraction`, `energy_ratio`, `cruise_flap_hz` (the gate has a flight-mode bar).
    pub modes: bool,
    /// `<entry>_energy_ratio` for each of these entries (the gate prices their energy,
    /// [`Gate::reference_max_energy_ratio`]).
    pub priced: Vec<String>,
    /// `identification_<axis>_fit_percent` (the gate has an identification bar).
    pub identification: bool,
}

impl GateColumns {
    pub fn of(gate: &Gate) -> Self {
        Self {
            modes: gate_asks_flight_modes(gate),
            priced: gate.reference_max_energy_ratio.keys().cloned().collect(),
            identification: gate.identification_fit_percent.is_some(),
        }
    }
}

impl Selection {
    /// The rows of `path` (none if it does not exist), for `references` in this order, with the
    /// gate's `columns`.
    pub fn read(path: &Path, references: &[String], columns: GateColumns) -> Result<Self, SelectionError> {
        if !path.exists() {
            return Ok(Self { rows: Vec::new(), columns });
        }
        let error = |message: String| SelectionError::File { path: path.to_owned(), message };
        let mut reader = csv::Reader::from_path(path).map_err(|e| error(e.to_string()))?;
        let expected = header(references, &columns);
        let headers: Vec<String> =
            reader.headers().map_err(|e| error(e.to_string()))?.iter().map(String::from).collect();
        if headers != expected {
            return Err(error(format!(
                "its columns are not those of this stage's validation set ({})",
                expected.join(",")
            )));
        }
        let mut rows = Vec::new();
        for (line, record) in reader.records().enumerate() {
            let record = record.map_err(|e| error(e.to_string()))?;
            let number = |k: usize| -> Result<f64, SelectionError> {
                record.get(k).and_then(|v| v.parse().ok()).ok_or_else(|| error(format!("row {}: column {k}", line + 2)))
            };
            let modes_column = FIXED.len() + 3 * references.len();
            let first_energy = modes_column + if columns.modes { MODE_COLUMNS.len() } else { 0 };
            let references = references
                .iter()
                .enumerate()
                .map(|(k, name)| {
                    let completed = number(FIXED.len() + 3 * k)? as usize;
                    let episodes = number(FIXED.len() + 3 * k + 1)? as usize;
                    let energy_ratio = match columns.priced.iter().position(|priced| priced == name) {
                        Some(j) => Some(number(first_energy + j)?),
                        None => None,
                    };
                    Ok(ReferenceScore {
                        name: name.clone(),
                        completed,
                        episodes,
                        mean_rms_m: number(FIXED.len() + 3 * k + 2)?,
                        energy_ratio,
                        flap_hz: None,
                    })
                })
                .collect::<Result<Vec<_>, SelectionError>>()?;
            let modes = if columns.modes {
                Some(ModeFigures {
                    glide_fraction: number(modes_column)?,
                    energy_ratio: number(modes_column + 1)?,
                    cruise_flap_hz: number(modes_column + 2)?,
                })
            } else {
                None
            };
            let first_fit = first_energy + columns.priced.len();
            let identification_fit_percent = match record.get(first_fit) {
                Some(text) if columns.identification && !text.is_empty() => {
                    Some([number(first_fit)?, number(first_fit + 1)?, number(first_fit + 2)?])
                }
                _ => None,
            };
            rows.push(Validated {
                iteration: number(0)? as usize,
                env_steps: number(1)? as u64,
                validation_s: number(4)?,
                score: Score { completed_percent: number(2)?, mean_rms_m: number(3)?, references },
                modes,
                identification_fit_percent,
            });
        }
        Ok(Self { rows, columns })
    }

    pub fn write(&self, path: &Path, references: &[String]) -> Result<(), SelectionError> {
        let rows = self.rows.iter().map(|row| {
            let mut values = vec![
                row.iteration.to_string(),
                row.env_steps.to_string(),
                // Shortest round-trip decimals: a resumed run ranks exactly what the uninterrupted one did.
                row.score.completed_percent.to_string(),
                row.score.mean_rms_m.to_string(),
                row.validation_s.to_string(),
            ];
            for r in &row.score.references {
                values.extend([r.completed.to_string(), r.episodes.to_string(), r.mean_rms_m.to_string()]);
            }
            if self.columns.modes {
                let f = row.modes.unwrap_or(ModeFigures::NOT_FLOWN);
                values.extend([f.glide_fraction, f.energy_ratio, f.cruise_flap_hz].map(|x| x.to_string()));
            }
            for name in &self.columns.priced {
                let ratio = row.score.energy_ratio(name).unwrap_or(f64::NAN);
                values.push(ratio.to_string());
            }
            if self.columns.identification {
                match row.identification_fit_percent {
                    Some(fits) => values.extend(fits.map(|fit| fit.to_string())),
                    None => values.extend([String::new(), String::new(), String::new()]),
                }
            }
            values
        });
        flapper_files::write_csv_rows(path, &header(references, &self.columns), rows)
            .map_err(|e| SelectionError::File { path: path.to_owned(), message: e.to_string() })
    }

    pub fn has(&self, iteration: usize) -> bool {
        self.rows.iter().any(|r| r.iteration == iteration)
    }

    /// Drops the rows after `iteration` (a run resumed from an earlier checkpoint redoes them).
    pub fn truncate_after(&mut self, iteration: usize) {
        self.rows.retain(|r| r.iteration <= iteration);
    }

    /// Whether a row at or after the gate's `min_iterations` meets it.
    pub fn gate_met(&self, gate: &Gate) -> bool {
        self.eligible(gate).next().is_some()
    }

    /// Whether a row before `iteration` met the gate (a run that met it there has stopped since).
    pub fn gate_met_before(&self, gate: &Gate, iteration: usize) -> bool {
        self.eligible(gate).any(|r| r.iteration < iteration)
    }

    /// The best checkpoint among those that meet the gate (the earliest of equals), else `None`.
    pub fn best_meeting<'a>(&'a self, gate: &'a Gate) -> Option<&'a Validated> {
        best(self.eligible(gate))
    }

    /// The best checkpoint among those that meet every bar of the gate but the identification's.
    pub fn best_flying<'a>(&'a self, gate: &'a Gate) -> Option<&'a Validated> {
        best(self.rows.iter().filter(|r| meets_flight_bars(gate, r)))
    }

    /// Where the gate's RMS bars are sought ([`Gate::rms_sought`]): the best checkpoint that meets its
    /// completion bars from `min_iterations` on, whatever its RMS errors, flight modes and identification.
    /// `None` where the RMS bars are required or no checkpoint completes.
    pub fn best_completing<'a>(&'a self, gate: &'a Gate) -> Option<&'a Validated> {
        if !gate.rms_sought {
            return None;
        }
        best(self.rows.iter().filter(|r| r.iteration >= gate.min_iterations && r.score.completes(gate)))
    }

    /// Where the gate's randomized entries are sought ([`Gate::randomized_sought`]): the best checkpoint
    /// that completes every named entry from `min_iterations` on and meets the RMS bars unless those are
    /// sought too, whatever its randomized entries, flight modes and identification. `None` where they
    /// are required or no checkpoint completes the named entries.
    pub fn best_completing_named<'a>(&'a self, gate: &'a Gate) -> Option<&'a Validated> {
        if !gate.randomized_sought {
            return None;
        }
        let flies = |r: &&Validated| r.score.completes_named(gate) && (gate.rms_sought || r.score.rms_met(gate));
        best(self.rows.iter().filter(|r| r.iteration >= gate.min_iterations).filter(flies))
    }

    /// Where the gate's flight-mode bars are sought ([`Gate::flight_modes_required`] unset): among the
    /// checkpoints that meet every tracking bar (from `min_iterations` on), the one that meets the most
    /// flight-mode bars, then flies with the least energy ([`energy_to_break_ties`]; the best score, then
    /// the earliest, of equals). `None` where the gate asks no flight mode, requires them, or no
    /// checkpoint tracks.
    pub fn most_efficient_tracking<'a>(&'a self, gate: &'a Gate) -> Option<&'a Validated> {
        self.most_efficient_tracking_from(gate, gate.min_iterations)
    }

    /// [`Self::most_efficient_tracking`] among the checkpoints from `iteration` on: from 0, also those
    /// before the gate's `min_iterations`, which a stage hands over only when none after tracks (a stage
    /// 5 that its budget cut short at 400 iterations tracked every bar at 150 and at no validation after).
    pub fn most_efficient_tracking_from<'a>(&'a self, gate: &'a Gate, iteration: usize) -> Option<&'a Validated> {
        if !gate_asks_flight_modes(gate) || gate.flight_modes_required {
            return None;
        }
        let energy = |r: &Validated| energy_to_break_ties(gate, r);
        let tracking: Vec<(&Validated, usize, f64)> = self
            .rows
            .iter()
            .filter(|r| r.iteration >= iteration && r.score.meets(gate))
            .map(|r| (r, flight_mode_bars_met(gate, r.modes.as_ref(), &r.score), energy(r)))
            .collect();
        let most = tracking.iter().map(|&(_, met, _)| met).max()?;
        let least =
            tracking.iter().filter(|&&(_, met, _)| met == most).map(|&(_, _, e)| e).fold(f64::INFINITY, f64::min);
        best(tracking.into_iter().filter(|&(_, met, e)| met == most && e == least).map(|(r, _, _)| r))
    }

    /// The best checkpoint of all, gate or not.
    pub fn best(&self) -> Option<&Validated> {
        best(self.rows.iter())
    }

    /// Whether the stage is still learning: the best of its last `window` validations beats the best of
    /// those before it (more episodes completed, or as many with a mean RMS error at least
    /// [`IMPROVEMENT_RMS`] smaller). `None` with fewer than `2 window` validations or no improvement.
    pub fn still_improving(&self, window: usize) -> Option<Improvement> {
        self.trend(window).filter(|t| t.improving())
    }

    /// The best of the last `window` validations against the best of those before it, improving or not;
    /// `None` with fewer than `2 window` validations.
    pub fn trend(&self, window: usize) -> Option<Improvement> {
        if window == 0 || self.rows.len() < 2 * window {
            return None;
        }
        let split = self.rows.len() - window;
        let earlier = best(self.rows[..split].iter())?;
        let recent = best(self.rows[split..].iter())?;
        let (e, r) = (&earlier.score, &recent.score);
        Some(Improvement {
            earlier_iteration: earlier.iteration,
            earlier_completed_percent: e.completed_percent,
            earlier_rms_m: e.mean_rms_m,
            recent_iteration: recent.iteration,
            recent_completed_percent: r.completed_percent,
            recent_rms_m: r.mean_rms_m,
        })
    }

    fn eligible<'a>(&'a self, gate: &'a Gate) -> impl Iterator<Item = &'a Validated> {
        self.rows.iter().filter(|r| {
            meets_flight_bars(gate, r)
                && gate
                    .identification_fit_percent
                    .is_none_or(|bar| meets_identification_bar(r.identification_fit_percent, bar))
        })
    }
}

/// The share by which a stage's best mean RMS error must fall, at equal completion, to count as learning.
pub const IMPROVEMENT_RMS: f64 = 0.05;

/// A stage's recent validations beating its earlier ones ([`Selection::still_improving`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Improvement {
    pub earlier_iteration: usize,
    pub earlier_completed_percent: f64,
    pub earlier_rms_m: f64,
    pub recent_iteration: usize,
    pub recent_completed_percent: f64,
    pub recent_rms_m: f64,
}

impl Improvement {
    /// More episodes completed recently, or as many with a mean RMS error at least [`IMPROVEMENT_RMS`]
    /// smaller.
    pub fn improving(&self) -> bool {
        self.recent_completed_percent > self.earlier_completed_percent
            || (self.recent_completed_percent == self.earlier_completed_percent
                && self.recent_rms_m <= (1.0 - IMPROVEMENT_RMS) * self.earlier_rms_m)
    }

    /// In words, for the log and `summary.json`: "still improving: ..." or "stalled: ...".
    pub fn describe(&self, window: usize) -> String {
        let (verdict, verb) =
            if self.improving() { ("still improving", "beats") } else { ("stalled", "does not beat") };
        format!(
            "{verdict}: the best of the last {window} validations (iteration {}: {:.1}% completed, RMS {:.3} m) {verb} the best before them (iteration {}: {:.1}%, {:.3} m)",
            self.recent_iteration,
            self.recent_completed_percent,
            self.recent_rms_m,
            self.earlier_iteration,
            self.earlier_completed_percent,
            self.earlier_rms_m
        )
    }
}

/// A stage given more iterations because it was still learning when its budget ran out, as
/// `stageK/extensions.json` and `summary.json` record it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Extension {
    /// The stage's budget when it ran out, and the iterations added to it.
    pub at_iteration: usize,
    pub added_iterations: usize,
    pub reason: String,
    /// Set where the stage had stalled and its exploration was restarted instead: the action noise
    /// (standard deviation) its last checkpoint continued with (the stage's `restart_noise_std`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restart_noise_std: Option<f32>,
    /// Set where the restart went back to the stage's best checkpoint (`restart_from_best`): its
    /// iteration, whose learner the restart continued with (absent: the last checkpoint's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restart_from_iteration: Option<usize>,
}

/// Whether a validated checkpoint meets every bar of `gate` but the identification's (which is looked
/// at only then): its iteration, its validation score and its flight modes.
pub fn meets_flight_bars(gate: &Gate, row: &Validated) -> bool {
    row.iteration >= gate.min_iterations
        && row.score.meets(gate)
        && meets_flight_mode_bars(gate, row.modes.as_ref(), &row.score)
}

/// How much energy a tracking checkpoint spends, for [`Selection::most_efficient_tracking`] to choose
/// among those meeting as many flight-mode bars: where the gate prices named entries
/// ([`Gate::reference_max_energy_ratio`]), the largest of their ratios over their bars -- the entry
/// furthest from (or nearest to failing) its bar, over the validation's starts -- else the exact-start
/// longitudinal flight's ratio to the scripted gait's (blind to every other reference). Unmeasured or
/// not flown to its end (NaN, missing): the least efficient, infinity.
pub fn energy_to_break_ties(gate: &Gate, row: &Validated) -> f64 {
    let finite = |ratio: Option<f64>| ratio.filter(|r| r.is_finite()).unwrap_or(f64::INFINITY);
    if gate.reference_max_energy_ratio.is_empty() {
        return finite(row.modes.as_ref().map(|f| f.energy_ratio));
    }
    gate.reference_max_energy_ratio
        .iter()
        .map(|(name, bar)| finite(row.score.energy_ratio(name)) / bar)
        .fold(0.0, f64::max)
}

fn best<'a>(rows: impl Iterator<Item = &'a Validated>) -> Option<&'a Validated> {
    rows.fold(None, |best: Option<&Validated>, row| match best {
        Some(b) if !row.score.beats(&b.score) => Some(b),
        _ => Some(row),
    })
}

/// The fixed columns; each reference then adds `<name>_completed`, `<name>_episodes`, `<name>_rms_m`,
/// then a table with a flight-mode bar has [`MODE_COLUMNS`] and `<entry>_energy_ratio` for each entry whose
/// energy its gate prices, and one with identification ends with `identification_<axis>_fit_percent` for
/// x, y and z.
const FIXED: [&str; 5] = ["iteration", "env_steps", "completed_percent", "mean_rms_m", "validation_s"];

/// The flight-mode columns ([`ModeFigures`]).
const MODE_COLUMNS: [&str; 3] = ["glide_fraction", "energy_ratio", "cruise_flap_hz"];

fn header(references: &[String], gate_columns: &GateColumns) -> Vec<String> {
    let mut columns: Vec<String> = FIXED.iter().map(|c| c.to_string()).collect();
    for name in references {
        columns.extend([format!("{name}_completed"), format!("{name}_episodes"), format!("{name}_rms_m")]);
    }
    if gate_columns.modes {
        columns.extend(MODE_COLUMNS.map(String::from));
    }
    columns.extend(gate_columns.priced.iter().map(|name| format!("{name}_energy_ratio")));
    if gate_columns.identification {
        columns.extend(AXES.map(|axis| format!("identification_{axis}_fit_percent")));
    }
    columns
}

/// What a finished stage hands over (`selected.json` in its folder).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageOutcome {
    pub stage: usize,
    pub name: String,
    /// Iterations trained (the last checkpoint) and their environment steps.
    pub iterations: usize,
    pub env_steps: u64,
    /// Training plus validation.
    pub wall_time_s: f64,
    /// Of `wall_time_s`, the time spent flying validations (and identifications): the rest trained.
    /// Absent in runs recorded before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub validation_wall_time_s: Option<f64>,
    pub selected_iteration: usize,
    /// The selected checkpoint's completion over the validation set (percent) and mean RMS error (m).
    pub validation_score: f64,
    pub validation_rms_m: f64,
    /// The selected checkpoint, relative to the curriculum folder.
    pub checkpoint: PathBuf,
    /// The budget extensions the stage was given (none: absent).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub extensions: Vec<Extension>,
    /// Whether the selected checkpoint met the gate's identification bar; absent where the gate has
    /// none. `false` when no checkpoint met it within the budget and the best flying one was handed over.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identification_met: Option<bool>,
    /// `false` where no checkpoint met the gate's flight-mode bars within the budget and the most efficient
    /// one that meets every tracking bar was handed over ([`crate::config::Gate::flight_modes_required`]);
    /// absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flight_modes_met: Option<bool>,
    /// `false` where no checkpoint met the gate's RMS bars within the budget and the best one that meets
    /// its completion bars was handed over ([`crate::config::Gate::rms_sought`]); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_met: Option<bool>,
    /// `false` where no checkpoint met the gate's randomized entries within the budget and the best one
    /// that completes every named entry was handed over ([`crate::config::Gate::randomized_sought`]);
    /// absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub randomized_met: Option<bool>,
    /// The selected checkpoint's flight modes ([`crate::flight_modes`]): its glide fraction, energy ratio
    /// and cruise flap frequency; absent where the gate has no flight-mode bar.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glide_fraction: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy_ratio: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cruise_flap_hz: Option<f64>,
    /// The CPU that finished the stage ([`crate::machine::cpu_model`]): training reproduces row for row
    /// on this CPU model, not on every one. Absent in runs recorded before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cpu: Option<String>,
}

/// A stage that missed its gate and stopped the run (`stopped` in `summary.json`): what it spent, and the
/// best checkpoint it reached, so that a stopped run's totals count the stage that stopped it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StoppedStage {
    pub stage: usize,
    pub name: String,
    /// The gate it missed, in words.
    pub gate: String,
    pub iterations: usize,
    pub env_steps: u64,
    /// Training plus validation.
    pub wall_time_s: f64,
    /// The best checkpoint by score (none where nothing was validated) and its completion (percent) and
    /// mean RMS error (m).
    pub best_iteration: Option<usize>,
    pub best_validation_score: Option<f64>,
    pub best_validation_rms_m: Option<f64>,
    pub cpu: Option<String>,
    /// The budget extensions and restarts it was given before it stopped (none: absent).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub extensions: Vec<Extension>,
    /// Why it was given no more iterations, in words (absent in runs recorded before it was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_because: Option<String>,
}

/// A stage's wall time, training and validation: the training log's clock (`trained_wall_time_s`, at the
/// last logged iteration) already runs through every validation done between iterations, as the
/// checkpoint hook runs inside training; only the validations of the last logged iteration or later
/// (the final one) come after it.
pub fn stage_wall_time_s(selection: &Selection, trained_wall_time_s: f64, last_iteration: usize) -> f64 {
    let after_last_log: f64 =
        selection.rows.iter().filter(|r| r.iteration >= last_iteration).map(|r| r.validation_s).sum();
    trained_wall_time_s + after_last_log
}

/// Of a stage's wall time, what its validations took (every validation flown, identifications included).
pub fn stage_validation_time_s(selection: &Selection) -> f64 {
    selection.rows.iter().map(|r| r.validation_s).sum()
}

#[cfg(test)]
impl Validated {
    /// A checkpoint that flew one validation reference, cruise, `completed` of 10 with a mean RMS error of
    /// `rms` (tests).
    pub(crate) fn of_cruise(iteration: usize, completed: usize, rms: f64) -> Self {
        let references = vec![ReferenceScore::flown("cruise", completed, 10, rms)];
        let score = Score { completed_percent: 10.0 * completed as f64, mean_rms_m: rms, references };
        Validated {
            iteration,
            env_steps: iteration as u64 * 100,
            validation_s: 1.5,
            score,
            modes: None,
            identification_fit_percent: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeMap;

    use super::*;

    use Validated as V;

    #[test]
    fn sought_rms_bars_fall_back_to_the_best_checkpoint_that_completes() {
        let selection = Selection {
            rows: vec![
                V::of_cruise(100, 10, 0.25), // before min_iterations: the only one within the bar
                V::of_cruise(200, 9, 0.40),  // completes too few
                V::of_cruise(300, 10, 0.45),
                V::of_cruise(400, 10, 0.35),
                V::of_cruise(500, 10, 0.38),
            ],
            columns: GateColumns::default(),
        };
        let bars = BTreeMap::from([("cruise".to_owned(), 0.3)]);
        let gate = Gate { reference_max_rms_m: bars, min_iterations: 200, ..Gate::completing(95.0) };
        assert!(selection.best_meeting(&gate).is_none(), "no checkpoint from 200 on within 0.3 m");
        assert!(selection.best_completing(&gate).is_none(), "required (the default): no fallback");
        let sought = Gate { rms_sought: true, ..gate.clone() };
        assert!(selection.best_meeting(&sought).is_none(), "sought, the bar still holds the gate shut");
        assert_eq!(selection.best_completing(&sought).map(|r| r.iteration), Some(400), "completes, least error");
        let mean = Gate { max_rms_m: Some(0.3), rms_sought: true, ..Gate::completing(95.0) };
        assert_eq!(selection.best_meeting(&mean).map(|r| r.iteration), Some(100), "met: no fallback needed");
        let late = Gate { min_iterations: 600, ..sought };
        assert!(selection.best_completing(&late).is_none(), "nothing from 600 on");
    }

    #[test]
    fn sought_flight_modes_fall_back_to_the_most_efficient_tracking_checkpoint() {
        let with = |iteration, completed, energy_ratio: f64, cruise_flap_hz| Validated {
            modes: Some(ModeFigures { glide_fraction: 0.0, energy_ratio, cruise_flap_hz }),
            ..V::of_cruise(iteration, completed, 0.2)
        };
        let selection = Selection {
            rows: vec![
                with(100, 10, 1.10, 5.0), // before min_iterations
                with(200, 8, 1.15, 5.0),  // does not track
                with(300, 10, 1.30, 6.5), // the flap out of its range
                with(400, 10, 1.40, 5.0),
                with(500, 10, 1.24, 5.9),
                with(600, 10, f64::NAN, 5.0), // not flown to its end
            ],
            columns: GateColumns::default(),
        };
        let gate = Gate {
            max_energy_ratio: Some(1.2),
            cruise_flap_hz: Some([4.0, 6.0]),
            min_iterations: 200,
            ..Gate::completing(90.0)
        };
        assert!(selection.best_meeting(&gate).is_none(), "no checkpoint meets 1.2 x");
        assert_eq!(selection.most_efficient_tracking(&gate).map(|r| r.iteration), Some(500), "flap met, least energy");
        assert_eq!(selection.most_efficient_tracking_from(&gate, 0).map(|r| r.iteration), Some(100), "earlier too");
        let late = Gate { min_iterations: 700, ..gate.clone() };
        assert!(selection.most_efficient_tracking(&late).is_none(), "nothing tracks from 700 on");
        let required = Gate { flight_modes_required: true, ..gate.clone() };
        assert!(selection.most_efficient_tracking(&required).is_none(), "required: no fallback");
        assert!(selection.most_efficient_tracking(&Gate::completing(90.0)).is_none(), "no flight-mode bar asked");
    }

    #[test]
    fn priced_entries_break_ties_by_their_largest_ratio_over_its_bar() {
        // Cruise priced at 3 x, longitudinal at 1.5 x; each row: exact-start ratio, cruise, longitudinal.
        let with = |iteration, exact: f64, cruise: Option<f64>, longitudinal: Option<f64>| {
            let mut row = V::of_cruise(iteration, 10, 0.2);
            row.score.references[0].energy_ratio = cruise;
            row.score.references.push(ReferenceScore {
                energy_ratio: longitudinal,
                ..ReferenceScore::flown("longitudinal", 10, 10, 0.2)
            });
            Validated {
                modes: Some(ModeFigures { glide_fraction: 0.0, energy_ratio: exact, cruise_flap_hz: 5.0 }),
                ..row
            }
        };
        let selection = Selection {
            rows: vec![
                with(100, 1.00, Some(3.3), Some(1.70)), // the least exact-start energy, both entries over their bars
                with(200, 1.30, Some(3.2), Some(1.65)), // over by 1.10 (longitudinal) and 1.07 (cruise)
                with(300, 1.40, Some(3.6), Some(1.55)), // over by 1.20 at the cruise
                with(400, 1.25, None, Some(1.6)),       // cruise not flown: the least efficient
            ],
            columns: GateColumns::default(),
        };
        let priced = BTreeMap::from([("cruise".to_owned(), 3.0), ("longitudinal".to_owned(), 1.5)]);
        let gate = Gate {
            max_energy_ratio: Some(0.9),
            reference_max_energy_ratio: priced,
            min_iterations: 100,
            ..Gate::completing(90.0)
        };
        let ties: Vec<f64> = selection.rows.iter().map(|r| energy_to_break_ties(&gate, r)).collect();
        assert!((ties[0] - 1.7 / 1.5).abs() < 1e-12 && (ties[1] - 1.1).abs() < 1e-12, "{ties:?}");
        assert!((ties[2] - 1.2).abs() < 1e-12 && ties[3].is_infinite(), "{ties:?}");
        // Every row meets no bar: 200 is furthest under, not 100 (the least exact-start energy).
        assert_eq!(selection.most_efficient_tracking(&gate).map(|r| r.iteration), Some(200));
        // Without priced entries the exact-start ratio decides, as before.
        let unpriced = Gate { reference_max_energy_ratio: BTreeMap::new(), ..gate.clone() };
        assert_eq!(energy_to_break_ties(&unpriced, &selection.rows[1]), 1.30);
        assert_eq!(selection.most_efficient_tracking(&unpriced).map(|r| r.iteration), Some(100));
    }

    #[test]
    fn a_stage_is_still_improving_when_its_recent_best_beats_its_earlier_best() {
        let rows = |scores: &[(usize, f64)]| Selection {
            rows: scores.iter().enumerate().map(|(k, &(c, rms))| V::of_cruise(100 * (k + 1), c, rms)).collect(),
            columns: GateColumns::default(),
        };
        // More completed in the last 2 than ever before.
        let climbing = rows(&[(3, 0.9), (6, 0.8), (5, 0.7), (7, 0.6)]);
        let improvement = climbing.still_improving(2).expect("7 of 10 beats 6 of 10");
        assert_eq!((improvement.recent_iteration, improvement.earlier_iteration), (400, 200));
        assert!(improvement.describe(2).contains("iteration 400: 70.0%"), "{}", improvement.describe(2));
        // As many completed, the error 10% smaller: improving; 2% smaller: not.
        assert!(rows(&[(8, 0.50), (8, 0.52), (8, 0.45), (7, 0.5)]).still_improving(2).is_some());
        assert!(rows(&[(8, 0.50), (8, 0.52), (8, 0.49), (7, 0.5)]).still_improving(2).is_none());
        // A plateau or a decline is not improving; too few validations say nothing.
        assert!(rows(&[(9, 0.5), (6, 0.6), (8, 0.5), (9, 0.5)]).still_improving(2).is_none());
        assert!(rows(&[(3, 0.9), (6, 0.8), (7, 0.7)]).still_improving(2).is_none());
        assert!(climbing.still_improving(0).is_none());
    }

    #[test]
    fn a_stages_wall_time_counts_each_validation_once() {
        // Validations at 10 and 20 ran inside training (its clock reads 100 s at iteration 20); the one at
        // 20 ran after that row was logged, so it alone is added.
        let selection = Selection {
            rows: vec![V::of_cruise(10, 8, 0.5), V::of_cruise(20, 10, 0.4)],
            columns: GateColumns::default(),
        };
        assert_eq!(stage_wall_time_s(&selection, 100.0, 20), 101.5);
        assert_eq!(stage_wall_time_s(&selection, 100.0, 21), 100.0, "a stage that trained past its last validation");
        assert_eq!(stage_validation_time_s(&selection), 1.5 * selection.rows.len() as f64);
    }

    #[test]
    fn the_best_checkpoint_is_chosen_by_completion_then_error_never_simply_the_last() {
        let selection = Selection {
            rows: vec![
                V::of_cruise(10, 8, 0.5),
                V::of_cruise(20, 10, 0.4),
                V::of_cruise(30, 10, 0.3),
                V::of_cruise(40, 9, 0.1),
            ],
            columns: GateColumns::default(),
        };
        assert_eq!(selection.best().unwrap().iteration, 30);
        let gate = Gate { max_rms_m: Some(0.35), ..Gate::completing(100.0) };
        assert_eq!(selection.best_meeting(&gate).unwrap().iteration, 30);
        let later = Gate { min_iterations: 35, ..gate.clone() };
        assert!(selection.best_meeting(&later).is_none() && !selection.gate_met(&later));
        let identified = Gate { identification_fit_percent: Some(80.0), max_rms_m: None, ..gate.clone() };
        let columns = GateColumns::of(&identified);
        let mut with_fits = Selection { columns, ..selection.clone() };
        assert!(with_fits.best_meeting(&identified).is_none(), "flown well, not identified: not eligible");
        with_fits.rows[2].identification_fit_percent = Some([85.0, 79.0, 90.0]);
        with_fits.rows[1].identification_fit_percent = Some([85.0, 81.0, 90.0]);
        assert_eq!(with_fits.best_meeting(&identified).unwrap().iteration, 20, "30 flies better, 20 is identified");
        assert_eq!(with_fits.best().unwrap().iteration, 30, "the best of all ignores the identification");
        assert_eq!(with_fits.best_flying(&identified).unwrap().iteration, 30, "flying bars only");
        assert!(with_fits.best_flying(&later).is_none(), "before min_iterations nothing flies the gate");
        let ties = Selection {
            rows: vec![V::of_cruise(10, 10, 0.3), V::of_cruise(20, 10, 0.3)],
            columns: GateColumns::default(),
        };
        assert_eq!(ties.best().unwrap().iteration, 10, "the earliest of equal checkpoints");
    }

    #[test]
    fn a_glide_bar_is_a_flight_bar_that_a_checkpoint_not_gliding_or_not_measured_misses() {
        let gate = Gate { glide_fraction: Some(0.5), ..Gate::completing(100.0) };
        let mut selection = Selection {
            rows: vec![V::of_cruise(10, 10, 0.2), V::of_cruise(20, 10, 0.3), V::of_cruise(30, 10, 0.4)],
            columns: GateColumns::of(&gate),
        };
        assert!(!selection.gate_met(&gate) && selection.best_flying(&gate).is_none(), "nothing measured");
        let glide = |share: f64| Some(ModeFigures { glide_fraction: share, energy_ratio: 1.2, cruise_flap_hz: 5.3 });
        selection.rows[0].modes = glide(f64::NAN);
        selection.rows[1].modes = glide(0.49);
        selection.rows[2].modes = glide(0.62);
        assert_eq!(
            selection.best_meeting(&gate).unwrap().iteration,
            30,
            "the only one that glides, not the best flown"
        );
        assert_eq!(selection.best_flying(&gate).unwrap().iteration, 30);
        assert_eq!(selection.best().unwrap().iteration, 10, "the best of all ignores the glide");
        let lower = Gate { glide_fraction: Some(0.4), ..gate.clone() };
        assert_eq!(selection.best_meeting(&lower).unwrap().iteration, 20);
    }

    #[test]
    fn the_table_reads_back_as_written_and_refuses_another_validation_set() {
        let dir = std::env::temp_dir().join(format!("flapper-selection-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("selection.csv");
        let names = vec!["cruise".to_owned()];
        let none = GateColumns::default();
        let selection =
            Selection { rows: vec![V::of_cruise(10, 8, 0.5), V::of_cruise(20, 10, 0.25)], columns: none.clone() };
        selection.write(&path, &names).unwrap();
        let back = Selection::read(&path, &names, none.clone()).unwrap();
        assert_eq!(back.rows, selection.rows);
        let e = Selection::read(&path, &["loop".to_owned()], none.clone()).unwrap_err().to_string();
        assert!(e.contains("selection.csv") && e.contains("loop_completed"), "{e}");
        let identification = GateColumns { identification: true, ..none.clone() };
        let e = Selection::read(&path, &names, identification.clone()).unwrap_err().to_string();
        assert!(e.contains("identification_x_fit_percent"), "a table without the identification columns: {e}");
        let e = Selection::read(&path, &names, GateColumns { modes: true, ..none.clone() }).unwrap_err();
        assert!(e.to_string().contains("glide_fraction"), "a table without the flight-mode columns: {e}");
        let mut identified = Selection {
            rows: vec![V::of_cruise(10, 8, 0.5), V::of_cruise(20, 10, 0.25)],
            columns: identification.clone(),
        };
        identified.rows[1].identification_fit_percent = Some([81.25, 79.5, 90.0]);
        identified.write(&path, &names).unwrap();
        let back = Selection::read(&path, &names, identification).unwrap();
        assert_eq!(back.rows, identified.rows, "fits where identified, none where not");
        let both = GateColumns { modes: true, identification: true, ..none.clone() };
        let mut glided = Selection { columns: both.clone(), ..identified.clone() };
        glided.rows[0].modes = Some(ModeFigures { glide_fraction: 0.125, energy_ratio: 4.75, cruise_flap_hz: 6.25 });
        glided.rows[1].modes = Some(ModeFigures { glide_fraction: 0.75, energy_ratio: 1.5, cruise_flap_hz: 5.3 });
        glided.write(&path, &names).unwrap();
        let back = Selection::read(&path, &names, both.clone()).unwrap();
        assert_eq!(back.rows, glided.rows, "the flight-mode columns between the references and the fits");
        let header = std::fs::read_to_string(&path).unwrap().lines().next().unwrap().to_owned();
        assert!(header.ends_with("cruise_rms_m,glide_fraction,energy_ratio,cruise_flap_hz,identification_x_fit_percent,identification_y_fit_percent,identification_z_fit_percent"), "{header}");
        let priced = GateColumns { priced: names.clone(), ..both.clone() };
        let e = Selection::read(&path, &names, priced.clone()).unwrap_err().to_string();
        assert!(e.contains("cruise_energy_ratio"), "a table without the priced entries' columns: {e}");
        let mut paid = Selection { columns: priced.clone(), ..glided.clone() };
        paid.rows[0].score.references[0].energy_ratio = Some(3.125);
        paid.rows[1].score.references[0].energy_ratio = Some(1.75);
        paid.write(&path, &names).unwrap();
        let back = Selection::read(&path, &names, priced).unwrap();
        assert_eq!(back.rows, paid.rows, "each priced entry's energy ratio after the flight-mode columns");
        let header = std::fs::read_to_string(&path).unwrap().lines().next().unwrap().to_owned();
        assert!(header.contains("cruise_flap_hz,cruise_energy_ratio,identification_x_fit_percent"), "{header}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
