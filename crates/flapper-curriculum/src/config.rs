//! The curriculum in one TOML file (`configs/curriculum.toml`): a seed, the `[runner]` and `[ppo]`
//! settings every stage starts from, and one `[[stages]]` entry per stage with its task, budget,
//! validation set and gate. Each stage becomes an ordinary `flapper train` config ([`TrainConfig`]), so
//! every key a training config takes is available here with the same meaning and the same checks. A
//! file may build on another and hold only what differs (`extends`, [`crate::overlay`]).

use std::collections::BTreeMap;
use std::path::Path;

use flapper_task::config::RandomizationConfig;
use flapper_train::{TrainConfig, TrainConfigError};
use serde::{Deserialize, Serialize};

use crate::overlay::{self, OverlayError};

#[derive(Debug, thiserror::Error)]
pub enum CurriculumConfigError {
    #[error("cannot read curriculum config '{path}'")]
    Read { path: String, source: std::io::Error },
    #[error(transparent)]
    Overlay(#[from] OverlayError),
    #[error("curriculum config '{origin}': {message}")]
    Parse { origin: String, message: String },
    #[error("curriculum config '{origin}', stage {stage}: {source}")]
    Stage { origin: String, stage: usize, source: TrainConfigError },
}

/// The whole file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurriculumConfig {
    /// Stage k trains with seed `seed * 100 + k` and validates with seed `seed * 100 + k + 50`, so
    /// validation never flies a start that training drew.
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The whole run's budget in environment steps (the paper: "a full controller trained in about 30
    /// million steps"). Each stage trains at most what the stages before it left, in whole validation
    /// intervals, and never more than its own `max_iterations`; a stage left fewer iterations than its
    /// gate needs stops the run before it starts. Absent: the stages' own budgets only.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_env_steps: Option<u64>,
    /// `[runner]` keys shared by every stage (a stage's own `[stages.runner]` overrides them).
    #[serde(default)]
    pub runner: toml::Table,
    /// `[ppo]` keys shared by every stage.
    #[serde(default)]
    pub ppo: toml::Table,
    pub stages: Vec<StageConfig>,
}

fn default_seed() -> u64 {
    1
}

/// The most checkpoints one validation may average ([`StageConfig::average_checkpoints`]).
pub const MAX_AVERAGED_CHECKPOINTS: usize = 100;

/// One stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageConfig {
    /// What the stage teaches, for people ("cruise", "climb and dive", ...).
    pub name: String,
    /// The budget: PPO iterations at most (each collects envs x steps_per_env environment steps).
    pub max_iterations: usize,
    /// Fly the validation set every this many iterations (each is a checkpoint too).
    pub validate_every: usize,
    /// The action noise (standard deviation) this stage starts from, replacing the previous stage's.
    /// A sharp policy (small std) pins the adaptive learning rate at its floor: the KL of a Gaussian
    /// grows as (change of mean / std)^2. Ignored for the first stage (`[ppo] init_noise_std`).
    pub start_noise_std: Option<f32>,
    /// What a stage does when its budget is spent without meeting its gate and its validations have
    /// stalled (no better than before the last few): absent, it stops the run; set, it restarts its
    /// exploration once, continuing from its last checkpoint with the action noise reset to this
    /// standard deviation, for as many iterations as an extension gets (within the run's budget).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restart_noise_std: Option<f32>,
    /// With `restart_noise_std`: the restart continues from the stage's best checkpoint (the one its
    /// stall names: most references completed, then the smallest mean RMS error) instead of its last,
    /// for a stage whose validations peaked and then drifted back; the iteration count and the budget go on
    /// from the last. Absent (false), from the last.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub restart_from_best: bool,
    /// An optional stage: one that refines a controller the stages before it already made (the
    /// efficient flight of stage 5). Missing its gate (or too little budget left to start it) does not
    /// stop the run: the run ends with the previous stage's controller (the optional stages after it
    /// are not run), and `summary.json` says which gate was missed and why (`optional_stage_missed`).
    /// Only the last stages may be optional (no required stage after an optional one), and not the
    /// first.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub optional: bool,
    /// The iterations this stage keeps back from the extensions and restarts of the stages before it
    /// (never from their own budgets): absent, the fewest it needs to hand over
    /// ([`StageConfig::least_iterations`]), or none for an optional stage. A refinement whose result
    /// comes late and swings from checkpoint to checkpoint (the glide) can keep the budget that an
    /// extension of the stage before it would otherwise spend. At most its `max_iterations`; for a required
    /// stage at least its least iterations.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reserved_iterations: Option<usize>,
    /// Judge and hand over, at each validation, the mean of the weights of the last this many
    /// checkpoints of the stage (the one just saved and those before it; fewer early in the stage)
    /// instead of the checkpoint alone: stochastic weight averaging, for a fine-tuning stage whose
    /// neighbouring checkpoints swing (docs/training.md). Training itself goes on from the checkpoint.
    /// Absent or 1: no averaging.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub average_checkpoints: Option<usize>,
    pub validation: ValidationConfig,
    pub gate: Gate,
    /// `[stages.runner]`, `[stages.ppo]`, `[stages.task]`: as in a `flapper train` config.
    #[serde(default)]
    pub runner: toml::Table,
    #[serde(default)]
    pub ppo: toml::Table,
    #[serde(default)]
    pub task: toml::Table,
}

/// The references a stage's checkpoints are judged on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ValidationConfig {
    /// Named references (`flapper reference --help` lists them) or CSV files.
    #[serde(default)]
    pub references: Vec<String>,
    /// Procedural references drawn from the stage's own `[task.reference]` ranges with the validation seed.
    #[serde(default)]
    pub procedural: usize,
    /// Randomized starts per reference.
    pub episodes: usize,
    /// More (or fewer) starts for some of `references`, by name: a manoeuvre whose completion swings
    /// from checkpoint to checkpoint needs more starts than the rest to be judged as the evaluation's
    /// 100 starts will judge it (`{ aerobatic = 100 }`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub reference_episodes: BTreeMap<String, usize>,
    /// References flown again with the robot's dynamics and the wind drawn per episode, so that
    /// selection sees robustness too (the nominal flights cannot).
    #[serde(default)]
    pub randomized: Vec<RandomizedValidation>,
}

/// Some references flown under one randomization: each becomes a validation entry named
/// `<reference>~<name>` (for example `lateral~table3`) with its own completion and RMS error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RandomizedValidation {
    /// A short name for the setting (letters, digits, '-', '_', '.').
    pub name: String,
    pub references: Vec<String>,
    /// Episodes per reference, each with its own draw of the dynamics and its own start.
    pub episodes: usize,
    /// A `[task.randomization]` table, always on (`enabled` is implied): Table III's ranges where
    /// not given; an interval of [1, 1] or a zero switches an item off.
    #[serde(default)]
    pub randomization: RandomizationConfig,
}

impl StageConfig {
    /// The stage less what it does once its budget is spent (`restart_noise_std`, `restart_from_best`,
    /// `optional`, the gate's `rms_sought` and `randomized_sought`): what it trains and how it is judged.
    pub fn as_trained(&self) -> StageConfig {
        let gate = Gate { rms_sought: false, randomized_sought: false, ..self.gate.clone() };
        StageConfig {
            restart_noise_std: None,
            restart_from_best: false,
            optional: false,
            reserved_iterations: None,
            gate,
            ..self.clone()
        }
    }

    /// The fewest iterations the stage can hand over after: one validation interval, or its gate's
    /// `min_iterations` where that is later (a budget that leaves less stops the run before the stage).
    pub fn least_iterations(&self) -> usize {
        self.gate.min_iterations.max(self.validate_every)
    }

    /// What the stage keeps back from the extensions and restarts of an earlier stage
    /// (`reserved_iterations`, or by default its least iterations, none if optional). An optional stage
    /// keeps nothing back from a required one (`earlier_optional` false): a required stage that does not
    /// meet its gate ends the run with no controller, which no refinement after it can make up for.
    pub fn kept_back_iterations(&self, earlier_optional: bool) -> usize {
        if self.optional && !earlier_optional {
            return 0;
        }
        self.reserved_iterations.unwrap_or(self.fewest_kept_back())
    }

    /// What the stage keeps back without `reserved_iterations`, and the least it may reserve: its least
    /// iterations, or nothing for an optional stage.
    fn fewest_kept_back(&self) -> usize {
        if self.optional { 0 } else { self.least_iterations() }
    }
}

impl ValidationConfig {
    /// The names of the entries the named references make: each of `references`, then
    /// `<reference>~<name>` for each randomized one (the procedural ones are drawn later).
    pub fn entry_names(&self) -> Vec<String> {
        let randomized =
            self.randomized.iter().flat_map(|r| r.references.iter().map(|reference| r.entry_name(reference)));
        self.references.iter().cloned().chain(randomized).collect()
    }

    /// How many starts `reference` is flown from.
    pub fn episodes_of(&self, reference: &str) -> usize {
        self.reference_episodes.get(reference).copied().unwrap_or(self.episodes)
    }
}

/// Between a reference's name and its randomization's in a randomized entry: `lateral~table3`.
pub const RANDOMIZED_SEPARATOR: char = '~';

impl RandomizedValidation {
    /// The entry `reference` makes flown under this randomization: `lateral~table3`.
    pub fn entry_name(&self, reference: &str) -> String {
        format!("{reference}{RANDOMIZED_SEPARATOR}{}", self.name)
    }

    /// The randomization as flown (switched on).
    pub fn flown_randomization(&self) -> RandomizationConfig {
        RandomizationConfig { enabled: true, ..self.randomization.clone() }
    }
}

/// When a stage has done its job: checked at every validation from `min_iterations` on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gate {
    /// Every validation reference completed in at least this share of its episodes (percent); the
    /// procedural ones too unless `procedural_completed_percent` is given.
    pub completed_percent: f64,
    /// The procedural references judged together: all their episodes completed in at least this share
    /// (percent). A path drawn at random may ask for more than the robot can fly; one such path must
    /// not hold the gate shut while the named references and the other drawn paths are flown.
    pub procedural_completed_percent: Option<f64>,
    /// The mean RMS tracking error over all validation episodes at most this (m).
    pub max_rms_m: Option<f64>,
    /// Some validation entries' own mean RMS error at most this (m), by entry name (a reference of
    /// `validation.references`, or `<reference>~<name>` for a randomized one): the evaluation's
    /// per-reference bars, which the mean over all entries cannot see (`{ longitudinal = 0.3 }`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub reference_max_rms_m: BTreeMap<String, f64>,
    /// The bar of each randomized validation entry (percent), when it differs from `completed_percent`.
    pub randomized_completed_percent: Option<f64>,
    /// Every axis of the closed loop identified by `flapper sysid` (its default experiment) predicts
    /// its validation record with at least this fit (percent). Identifying takes minutes, so it is
    /// done only for checkpoints that meet every other bar of the gate (`identification`). This bar is
    /// sought, not required: the stage trains on until a checkpoint meets it with the others, and if
    /// none has when the budget is spent it hands over the best checkpoint that flies the other bars and
    /// records that the identification was not met (`identification_met` in `selected.json`). How well
    /// a model predicts the flight is a property of the analysis, not of the flying; it must not throw
    /// away a controller that flies every bar.
    pub identification_fit_percent: Option<f64>,
    /// `identification_fit_percent` required like every other bar: a stage none of whose checkpoints
    /// meets it stops the run with the gate's message instead of handing over one that flies the rest.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub identification_required: bool,
    /// The wings held for at least this share (0 to 1) of the longitudinal reference's glide segment,
    /// as `flapper modes` measures it (flap range below 10 deg over 0.4 s; one flight from the exact
    /// start, with every validation): the paper's "gliding instead of flapping when possible". A
    /// checkpoint that does not fly the reference to its end does not glide (NaN in the table).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glide_fraction: Option<f64>,
    /// The energy per metre of the same flight at most this many times the scripted gait's from the
    /// same start ([`crate::flight_modes`]): the paper's energy term, "gliding instead of flapping when
    /// possible", as a bar the stage selects on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_energy_ratio: Option<f64>,
    /// Some validation entries' energy per metre, the mean over their episodes, at most this many times
    /// the scripted gait's from the same starts, by entry name (`{ longitudinal = 1.5, immelmann = 3.0 }`):
    /// `flapper eval`'s energy ratio on every reference the issue prices, not only on the longitudinal
    /// flight from its exact start (`max_energy_ratio`, about 0.8 of the ratio over 100 starts). A
    /// flight-mode bar: sought unless `flight_modes_required`. The scripted gait flies each priced entry
    /// once per stage.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub reference_max_energy_ratio: BTreeMap<String, f64>,
    /// The flap's fundamental in the same flight's cruise segment (or the flight `cruise_flap_flight`
    /// names) within this range (Hz): the paper's 7 Hz filter "limit[s] the viable flapping
    /// frequencies to 4-6 Hz".
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cruise_flap_hz: Option<[f64; 2]>,
    /// The flight `cruise_flap_hz` reads the flap's fundamental from ([`CruiseFlapFlight`]).
    #[serde(default, skip_serializing_if = "CruiseFlapFlight::is_default")]
    pub cruise_flap_flight: CruiseFlapFlight,
    /// The flight-mode bars (`glide_fraction`, `max_energy_ratio`, `cruise_flap_hz`) are sought, not
    /// required, unless this is set: a stage that has spent its budget (extensions included) with
    /// checkpoints that meet every tracking bar but none that meets the flight-mode bars hands over the
    /// most efficient of them (the most flight-mode bars met, then the least energy per metre) and records
    /// `flight_modes_met: false` in `selected.json`, instead of stopping the run. How efficiently a
    /// controller flies must not throw away one that flies every manoeuvre (seed 4 missed 1.2 x at 1.24 x).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub flight_modes_required: bool,
    /// The RMS bars (`max_rms_m`, `reference_max_rms_m`) are sought, not required, where this is set: a
    /// stage that has spent its budget (extensions and restart included) without a checkpoint meeting
    /// the whole gate hands over the best one that meets its completion bars and records `rms_met: false`
    /// in `selected.json`, instead of stopping the run. The RMS bars are the shipped robot's evaluation
    /// bars; on a robot of one's own they must not throw away a controller that completes every
    /// reference (the tail-heavy robot's stage 4 flew every one 47-50 of 50 for 875 iterations with
    /// longitudinal at 0.33-0.40 m against 0.3).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub rms_sought: bool,
    /// The randomized entries' completion bars (`randomized_completed_percent`, or `completed_percent`
    /// where that is absent) are sought, not required, where this is set: a stage that has spent its
    /// budget (extensions and restart included) without a checkpoint meeting the whole gate hands over the
    /// best one that completes every named entry (and meets the RMS bars unless they are sought too) and
    /// records `randomized_met: false` in `selected.json`, instead of stopping the run. Flying under every
    /// fluid coefficient x0.7 is our robot's robustness bar; a robot of one's own with less lift to spare
    /// may not have it, and must still get the controller that flies its references
    /// (`configs/curriculum-transfer.toml`: the narrow robot flew longitudinal under it 80-97 of 100).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub randomized_sought: bool,
    /// The gate is not looked at before this iteration (a stage that just met it may still improve).
    #[serde(default)]
    pub min_iterations: usize,
}

/// Which flight a gate's `cruise_flap_hz` reads the flap's fundamental from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CruiseFlapFlight {
    /// The cruise segment (the first 6 s) of the longitudinal flight the glide and energy bars read:
    /// one flight for the three bars (every shipped run's gate). Its fundamental falls on a few values
    /// 0.25 Hz apart and read up to 1.2 Hz from the cruise reference's (docs/experiments.md, "A sharper
    /// position kernel for the glide stage").
    #[default]
    LongitudinalSegment,
    /// The cruise reference (30 s at 3.8 m/s) flown once more from its exact start, its fundamental
    /// after the first second as `flapper eval` takes it: the flight the efficient-bird bar reads (the
    /// eval table's flap_left row on cruise), for one more 30 s flight per validation. One start reads
    /// up to 0.5 Hz from the mean over 100 (6.17 Hz against 5.74 for the shipped sixth stage's pick).
    CruiseReference,
    /// The validation's own `cruise` entry: the flap's fundamental after the first second of each of its
    /// randomized starts, averaged as `flapper eval`'s table averages its starts (the same figure as
    /// the efficient-bird bar reads, from the validation's starts instead of the evaluation's); no extra
    /// flight. The validation must fly the cruise reference.
    ValidationStarts,
}

/// The validation entry [`CruiseFlapFlight::ValidationStarts`] reads the flap from.
pub const CRUISE_ENTRY: &str = "cruise";

impl CruiseFlapFlight {
    fn is_default(&self) -> bool {
        *self == Self::default()
    }
}

#[cfg(test)]
impl Gate {
    /// A gate with only its completion bar, for tests to add bars to.
    pub(crate) fn completing(completed_percent: f64) -> Self {
        Self {
            completed_percent,
            procedural_completed_percent: None,
            randomized_completed_percent: None,
            max_rms_m: None,
            reference_max_rms_m: BTreeMap::new(),
            identification_fit_percent: None,
            identification_required: false,
            glide_fraction: None,
            max_energy_ratio: None,
            reference_max_energy_ratio: BTreeMap::new(),
            cruise_flap_hz: None,
            cruise_flap_flight: CruiseFlapFlight::LongitudinalSegment,
            flight_modes_required: false,
            rms_sought: false,
            randomized_sought: false,
            min_iterations: 0,
        }
    }
}

/// A gate's bars per validation entry (`key`): each names an entry of the set and is positive and finite
/// (`what` a bar must be, for the message).
fn entry_bars(key: &str, bars: &BTreeMap<String, f64>, entries: &[String], what: &str) -> Result<(), String> {
    if let Some((name, _)) = bars.iter().find(|(name, _)| !entries.contains(name)) {
        return Err(format!("{key} names '{name}', which is not a validation entry ({})", entries.join(", ")));
    }
    if let Some((name, bar)) = bars.iter().find(|(_, bar)| !(**bar > 0.0 && bar.is_finite())) {
        return Err(format!("{key}: '{name}' needs {what}, got {bar}"));
    }
    Ok(())
}

impl CurriculumConfig {
    /// Reads, resolves (a file that extends another is laid over it) and checks a curriculum file.
    pub fn load(path: &Path) -> Result<Self, CurriculumConfigError> {
        let origin = path.display().to_string();
        let text = std::fs::read_to_string(path)
            .map_err(|source| CurriculumConfigError::Read { path: origin.clone(), source })?;
        let file: toml::Table = toml::from_str(&text).map_err(|e: toml::de::Error| CurriculumConfigError::Parse {
            origin: origin.clone(),
            message: e.to_string(),
        })?;
        if !overlay::extends_another(&file) {
            // Parsed again from the text, so that a mistake is shown at its line.
            return Self::from_toml(&text, &origin);
        }
        let resolved = overlay::resolve(path, file)?;
        let config = Self::deserialize(resolved)
            .map_err(|e| CurriculumConfigError::Parse { origin: origin.clone(), message: e.to_string() })?;
        config.checked(&origin)
    }

    /// Parses and checks a whole curriculum (one that extends no other file).
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, CurriculumConfigError> {
        let config: Self = toml::from_str(text).map_err(|e: toml::de::Error| CurriculumConfigError::Parse {
            origin: origin.to_owned(),
            message: e.to_string(),
        })?;
        config.checked(origin)
    }

    /// Checks the whole curriculum: every stage's training config is built once here, so a mistake in
    /// stage 4 is refused before stage 1 trains.
    fn checked(self, origin: &str) -> Result<Self, CurriculumConfigError> {
        let config = self;
        let parse = |message: String| CurriculumConfigError::Parse { origin: origin.to_owned(), message };
        if config.stages.is_empty() {
            return Err(parse("needs at least one [[stages]] entry".into()));
        }
        if config.max_env_steps == Some(0) {
            return Err(parse("max_env_steps must be at least 1 (or left out for no total budget)".into()));
        }
        for (index, stage) in config.stages.iter().enumerate() {
            let number = index + 1;
            let bad = |message: String| parse(format!("stage {number} ('{}'): {message}", stage.name));
            if stage.max_iterations == 0 || stage.validate_every == 0 || stage.validate_every > stage.max_iterations {
                return Err(bad(format!(
                    "max_iterations ({}) and validate_every ({}) must be at least 1, validate_every no more than max_iterations",
                    stage.max_iterations, stage.validate_every
                )));
            }
            let v = &stage.validation;
            if v.episodes == 0 || v.references.len() + v.procedural == 0 {
                return Err(bad("validation needs at least one reference (or procedural > 0) and episodes > 0".into()));
            }
            let g = &stage.gate;
            let percent = |p: f64| (0.0..=100.0).contains(&p);
            if !percent(g.completed_percent)
                || !g.procedural_completed_percent.is_none_or(percent)
                || !g.randomized_completed_percent.is_none_or(percent)
                || !g.identification_fit_percent.is_none_or(percent)
                || g.max_rms_m.is_some_and(|r| !(r > 0.0 && r.is_finite()))
            {
                return Err(bad(format!(
                    "gate.completed_percent, gate.procedural_completed_percent, gate.randomized_completed_percent \
                     and gate.identification_fit_percent must be in [0, 100] (got {}, {:?}, {:?} and {:?}) and \
                     gate.max_rms_m positive (got {:?})",
                    g.completed_percent,
                    g.procedural_completed_percent,
                    g.randomized_completed_percent,
                    g.identification_fit_percent,
                    g.max_rms_m
                )));
            }
            if g.glide_fraction.is_some_and(|share| !(0.0..=1.0).contains(&share)) {
                return Err(bad(format!("gate.glide_fraction is a share in [0, 1], got {:?}", g.glide_fraction)));
            }
            if g.max_energy_ratio.is_some_and(|ratio| !(ratio > 0.0 && ratio.is_finite())) {
                return Err(bad(format!(
                    "gate.max_energy_ratio must be a positive ratio, got {:?}",
                    g.max_energy_ratio
                )));
            }
            if let Some([low, high]) = g.cruise_flap_hz
                && !(low > 0.0 && low < high && high.is_finite())
            {
                return Err(bad(format!(
                    "gate.cruise_flap_hz is a range [low, high] of frequencies with 0 < low < high, got [{low}, {high}]"
                )));
            }
            if g.cruise_flap_flight == CruiseFlapFlight::ValidationStarts
                && !v.entry_names().iter().any(|name| name == CRUISE_ENTRY)
            {
                return Err(bad(format!(
                    "gate.cruise_flap_flight = \"validation_starts\" reads the flap on the validation's \
                     '{CRUISE_ENTRY}' entry: add \"{CRUISE_ENTRY}\" to validation.references (they are {})",
                    v.references.join(", ")
                )));
            }
            if g.identification_required && g.identification_fit_percent.is_none() {
                return Err(bad(
                    "gate.identification_required needs gate.identification_fit_percent, the bar it requires".into(),
                ));
            }
            if let Some((name, _)) = v.reference_episodes.iter().find(|(name, _)| !v.references.contains(name)) {
                return Err(bad(format!(
                    "validation.reference_episodes names '{name}', which is not among validation.references ({})",
                    v.references.join(", ")
                )));
            }
            if let Some((name, episodes)) = v.reference_episodes.iter().find(|(_, episodes)| **episodes == 0) {
                return Err(bad(format!("validation.reference_episodes: '{name}' needs episodes > 0, got {episodes}")));
            }
            let entries = v.entry_names();
            entry_bars("gate.reference_max_rms_m", &g.reference_max_rms_m, &entries, "a positive bar in metres")
                .map_err(&bad)?;
            entry_bars(
                "gate.reference_max_energy_ratio",
                &g.reference_max_energy_ratio,
                &entries,
                "a positive ratio to the scripted gait's energy per metre",
            )
            .map_err(&bad)?;
            if let Some(count) = stage.average_checkpoints
                && !(1..=MAX_AVERAGED_CHECKPOINTS).contains(&count)
            {
                return Err(bad(format!(
                    "average_checkpoints must be in [1, {MAX_AVERAGED_CHECKPOINTS}], got {count}"
                )));
            }
            if let Some(reserved) = stage.reserved_iterations {
                let least = stage.fewest_kept_back();
                if !(least..=stage.max_iterations).contains(&reserved) {
                    return Err(bad(format!(
                        "reserved_iterations must be in [{least}, {}], got {reserved} (at most the stage's max_iterations{})",
                        stage.max_iterations,
                        if stage.optional { "" } else { ", at least the iterations it needs to hand over" }
                    )));
                }
            }
            let required_after = config.stages[number..].iter().any(|later| !later.optional);
            if stage.optional && (number == 1 || required_after) {
                return Err(bad(format!(
                    "optional = true is allowed on the last stages only, after at least one required stage and \
                     with no required stage after it (this is stage {number} of {}): a missed optional stage \
                     ends the run with the previous stage's controller",
                    config.stages.len()
                )));
            }
            for (key, value) in
                [("start_noise_std", stage.start_noise_std), ("restart_noise_std", stage.restart_noise_std)]
            {
                if let Some(std) = value
                    && !(std > 0.0 && std <= 10.0)
                {
                    return Err(bad(format!("{key} must be in (0, 10], got {std}")));
                }
            }
            if stage.restart_from_best && stage.restart_noise_std.is_none() {
                return Err(bad(
                    "restart_from_best = true needs restart_noise_std (the restart it says where to begin from)"
                        .to_owned(),
                ));
            }
            let train = config.stage_train_config(number).map_err(|source| CurriculumConfigError::Stage {
                origin: origin.to_owned(),
                stage: number,
                source,
            })?;
            for r in &v.randomized {
                let named = !r.name.is_empty()
                    && r.name.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'));
                if !named || r.references.is_empty() || r.episodes == 0 {
                    return Err(bad(format!(
                        "validation.randomized '{}' needs a name of letters, digits, '-', '_' or '.', at least one \
                         reference and episodes > 0",
                        r.name
                    )));
                }
                let mut task = train.task.clone();
                task.randomization = r.flown_randomization();
                task.validate().map_err(|e| bad(format!("validation.randomized '{}': {e}", r.name)))?;
            }
        }
        Ok(config)
    }

    /// Stage `number`'s (1-based) `flapper train` config: the shared `[runner]` and `[ppo]`, then the
    /// stage's own tables over them; the seed, budget and checkpoint interval from the curriculum.
    pub fn stage_train_config(&self, number: usize) -> Result<TrainConfig, TrainConfigError> {
        let stage = &self.stages[number - 1];
        let mut runner = self.runner.clone();
        runner.extend(stage.runner.clone());
        runner.insert("seed".into(), toml::Value::Integer(self.stage_seed(number) as i64));
        runner.insert("iterations".into(), toml::Value::Integer(stage.max_iterations as i64));
        runner.insert("checkpoint_every".into(), toml::Value::Integer(stage.validate_every as i64));
        if number > 1
            && let Some(std) = stage.start_noise_std
        {
            runner.insert("init_from_noise_std".into(), toml::Value::Float(std as f64));
        }
        let mut ppo = self.ppo.clone();
        ppo.extend(stage.ppo.clone());
        let mut table = toml::Table::new();
        table.insert("runner".into(), toml::Value::Table(runner));
        table.insert("ppo".into(), toml::Value::Table(ppo));
        table.insert("task".into(), toml::Value::Table(stage.task.clone()));
        let text = toml::to_string(&table).expect("a TOML table serializes");
        TrainConfig::from_toml(&text, &format!("[[stages]] {number} ('{}')", stage.name), None)
    }

    /// Stage `number`'s budget in iterations once the stages before it spent `spent_env_steps`: its own
    /// `max_iterations`, or fewer where `max_env_steps` leaves less (rounded down to whole validation
    /// intervals, so that the last iteration is validated).
    pub fn stage_iterations(&self, number: usize, spent_env_steps: u64) -> Result<usize, TrainConfigError> {
        let stage = &self.stages[number - 1];
        let Some(total) = self.max_env_steps else { return Ok(stage.max_iterations) };
        let train = self.stage_train_config(number)?;
        let per_iteration = (train.runner.envs * train.ppo.steps_per_env) as u64;
        let left = (total.saturating_sub(spent_env_steps) / per_iteration) as usize;
        Ok(stage.max_iterations.min(left - left % stage.validate_every))
    }

    /// The iterations stage `number` may add to its budget once it has trained `trained` of them (its
    /// stages before it spent `spent_env_steps`): half its `max_iterations` at most, and no more than the
    /// run's `max_env_steps` leaves after the fewest iterations every later stage needs to hand over
    /// ([`StageConfig::kept_back_iterations`]: by default its least iterations, and an optional stage holds
    /// nothing back, a required stage meeting its gate mattering more than the refinement after it; its
    /// `reserved_iterations` hold only against optional stages); a multiple of `validate_every` (0: no room).
    /// Keeping back the later stages' whole `max_iterations` instead left no stage but the last any room: the shipped
    /// stages' caps add up to more than the run's budget by design, so a heavier robot's stage 2 still
    /// improving at its 400th iteration stopped the run with 27 M of the 30 M steps unspent.
    pub fn extension_iterations(
        &self,
        number: usize,
        spent_env_steps: u64,
        trained: usize,
    ) -> Result<usize, TrainConfigError> {
        let stage = &self.stages[number - 1];
        let per_iteration = |k: usize| -> Result<u64, TrainConfigError> {
            let train = self.stage_train_config(k)?;
            Ok((train.runner.envs * train.ppo.steps_per_env) as u64)
        };
        let mut room = stage.max_iterations / 2;
        if let Some(total) = self.max_env_steps {
            let mut reserved = spent_env_steps + trained as u64 * per_iteration(number)?;
            for later in number + 1..=self.stages.len() {
                let kept = self.stages[later - 1].kept_back_iterations(stage.optional);
                if kept > 0 {
                    reserved += kept as u64 * per_iteration(later)?;
                }
            }
            room = room.min((total.saturating_sub(reserved) / per_iteration(number)?) as usize);
        }
        Ok(room - room % stage.validate_every)
    }

    /// How many checkpoints stage `number`'s validations average (1: none).
    pub fn averaged_checkpoints(&self, number: usize) -> usize {
        self.stages[number - 1].average_checkpoints.unwrap_or(1)
    }

    pub fn stage_seed(&self, number: usize) -> u64 {
        self.seed * 100 + number as u64
    }

    pub fn validation_seed(&self, number: usize) -> u64 {
        self.stage_seed(number) + 50
    }

    /// The file as it will be saved with the run (every stage in full).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("the curriculum serializes")
    }
}

/// A curriculum of the repository's `configs/` (`file` relative to it), for tests.
#[cfg(test)]
pub(crate) fn shipped(file: &str) -> CurriculumConfig {
    CurriculumConfig::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs").join(file)).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    pub const TINY: &str = r#"
seed = 3
[runner]
envs = 4
threads = 1
[ppo]
steps_per_env = 8
[[stages]]
name = "cruise"
max_iterations = 4
validate_every = 2
validation = { references = ["cruise"], episodes = 1 }
gate = { completed_percent = 0 }
task = { stage = 1 }
[[stages]]
name = "climb and dive"
max_iterations = 2
validate_every = 1
start_noise_std = 0.4
validation = { references = ["longitudinal"], procedural = 1, episodes = 1 }
gate = { completed_percent = 0, max_rms_m = 100.0 }
runner = { envs = 2 }
task = { stage = 2 }
"#;

    #[test]
    fn stages_become_training_configs_with_the_shared_settings_and_their_own() {
        let c = CurriculumConfig::from_toml(TINY, "tiny.toml").unwrap();
        let first = c.stage_train_config(1).unwrap();
        let second = c.stage_train_config(2).unwrap();
        assert_eq!((first.runner.envs, second.runner.envs), (4, 2), "a stage's [runner] overrides the shared one");
        assert_eq!((first.ppo.steps_per_env, second.ppo.steps_per_env), (8, 8));
        assert_eq!((first.runner.seed, second.runner.seed), (301, 302));
        assert_eq!((first.runner.iterations, first.runner.checkpoint_every), (4, 2));
        assert_eq!((first.task.stage, second.task.stage), (1, 2));
        assert_eq!(first.runner.init_from_noise_std, None);
        assert_eq!(second.runner.init_from_noise_std, Some(0.4));
        assert_ne!(c.validation_seed(1), first.runner.seed);
        let again = CurriculumConfig::from_toml(&c.to_toml(), "saved").unwrap();
        assert_eq!(again, c, "the saved curriculum reads back as it was");
    }

    #[test]
    fn a_stage_extends_by_half_its_budget_within_what_the_run_leaves_after_the_later_stages() {
        let mut c = CurriculumConfig::from_toml(TINY, "tiny.toml").unwrap();
        // No run budget: half of stage 1's 4 iterations, a multiple of its validation interval (2).
        assert_eq!(c.extension_iterations(1, 0, 4).unwrap(), 2);
        // Stage 1 takes 32 steps an iteration; stage 2 16, and it needs 1 iteration to hand over (its
        // validation interval; no min_iterations), so 16 steps are kept back for it, not its whole
        // max_iterations (2, 32 steps).
        assert_eq!(c.stages[1].least_iterations(), 1);
        c.max_env_steps = Some(4 * 32 + 2 * 32 + 16);
        assert_eq!(c.extension_iterations(1, 0, 4).unwrap(), 2, "room for 2 more, half the budget caps it");
        c.max_env_steps = Some(4 * 32 + 32 + 16);
        assert_eq!(c.extension_iterations(1, 0, 4).unwrap(), 0, "room for 1, not a whole validation interval");
        c.max_env_steps = Some(4 * 32 + 16);
        assert_eq!(c.extension_iterations(1, 0, 4).unwrap(), 0, "nothing of what the later stage needs");
        // A later stage's min_iterations is kept back whole: at 3 stage 2 needs 48 steps.
        c.stages[1].gate.min_iterations = 3;
        c.max_env_steps = Some(4 * 32 + 2 * 32 + 48);
        assert_eq!(c.extension_iterations(1, 0, 4).unwrap(), 2);
        c.max_env_steps = Some(4 * 32 + 2 * 32 + 32);
        assert_eq!(c.extension_iterations(1, 0, 4).unwrap(), 0, "48 steps kept for stage 2 leave 1 iteration");
        // The last stage keeps nothing back: 1 iteration of 16 steps left after 64 spent and 2 trained.
        c.max_env_steps = Some(64 + 2 * 16 + 16);
        assert_eq!(c.extension_iterations(2, 64, 2).unwrap(), 1);
    }

    /// The run's budget is set, within the paper's 30 M steps, and leaves every stage room to start after
    /// the shortest stages before it (each at its gate's `min_iterations` or one validation interval).
    fn check_budget(c: &CurriculumConfig, file: &str) {
        let budget = c.max_env_steps.expect("the run's budget is set");
        assert!(budget <= 30_000_000, "{file}: the budget is {budget} environment steps, over the paper's 30 M");
        let mut shortest = 0;
        for k in 1..=c.stages.len() {
            let needed = c.stages[k - 1].least_iterations();
            assert!(c.stage_iterations(k, shortest).unwrap() >= needed, "{file}: stage {k} would never start");
            let t = c.stage_train_config(k).unwrap();
            shortest += (needed * t.runner.envs * t.ppo.steps_per_env) as u64;
        }
    }

    /// The environment steps seed 1's shipped stages 1-4 trained (2504 iterations of 6144 steps).
    const SEED1_BEFORE_STAGE5: u64 = 2504 * 6144;

    fn task_stages(c: &CurriculumConfig) -> Vec<u8> {
        (1..=c.stages.len()).map(|k| c.stage_train_config(k).unwrap().task.stage).collect()
    }

    /// Each stage's share of training episodes that start along their path.
    fn path_start_probabilities(c: &CurriculumConfig) -> Vec<f64> {
        (1..=c.stages.len())
            .map(|k| c.stage_train_config(k).unwrap().task.initial_state.path_start_probability)
            .collect()
    }

    #[test]
    fn the_shipped_curriculum_reads_and_fits_the_papers_budget() {
        let c = shipped("curriculum.toml");
        assert_eq!(
            task_stages(&c),
            [1, 2, 3, 4, 4, 4, 4],
            "the paper's four stages in order, then the efficient flight, the efficient manoeuvres and the glide"
        );
        assert_eq!(
            path_start_probabilities(&c),
            [0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0],
            "stage 3's episodes start along their paths, and no other's"
        );
        let restarts: Vec<Option<f32>> = c.stages.iter().map(|s| s.restart_noise_std).collect();
        assert_eq!(restarts, [None, None, Some(0.4), Some(0.4), None, None, None], "stalled, stages 3 and 4 restart");
        let optional: Vec<bool> = c.stages.iter().map(|s| s.optional).collect();
        assert_eq!(
            optional,
            [false, false, false, false, true, true, true],
            "a missed refinement leaves the one before"
        );
        let rms_sought: Vec<bool> = c.stages.iter().map(|s| s.gate.rms_sought).collect();
        assert_eq!(
            rms_sought,
            [false, true, false, true, false, false, false],
            "stages 2 and 4 hand over one that completes"
        );
        assert!(!c.stages[3].gate.reference_max_rms_m.is_empty(), "with its RMS bars");
        assert_eq!(c.stages[3].as_trained(), c.stages[3].as_trained().as_trained(), "as trained: idempotent");
        assert!(!c.stages[3].as_trained().gate.rms_sought, "decided at the budget's end: not part of training");
        let efficient = c.stage_train_config(5).unwrap();
        assert!(efficient.ppo.smoothness_coef > 0.0 && efficient.task.reference.glide_probability > 0.0);
        let gate = &c.stages[4].gate;
        assert!(gate.max_energy_ratio.is_some() && gate.cruise_flap_hz == Some([4.0, 6.0]));
        assert_eq!(c.stages[4].validation, c.stages[3].validation, "judged on stage 4's validation set");
        // The sixth stage: stage 5's task and validation set, the energy priced nearly linearly, every named
        // reference's energy judged at validation, the flap read on the validation's own cruise starts.
        let manoeuvres = c.stage_train_config(6).unwrap();
        assert_eq!(c.stages[5].validation, c.stages[4].validation, "judged on stage 5's validation set");
        assert_eq!((manoeuvres.task.reward.energy_weight, manoeuvres.task.reward.energy_scale_w), (0.3, 100.0));
        assert_eq!(manoeuvres.task.reward.position_scale_m, 0.85);
        assert_eq!(manoeuvres.ppo, efficient.ppo, "stage 5's learner settings");
        let priced = &c.stages[5].gate.reference_max_energy_ratio;
        assert_eq!(priced.len(), 8, "every named reference's energy priced: {priced:?}");
        assert_eq!((priced["longitudinal"], priced["immelmann"]), (1.45, 2.9));
        let gate = &c.stages[5].gate;
        assert_eq!(gate.cruise_flap_flight, CruiseFlapFlight::ValidationStarts, "the flap as `flapper eval` reads it");
        assert!(c.stages[5].validation.references.iter().any(|r| r == CRUISE_ENTRY));
        // The seventh stage: the sixth's task, price, validation set and gate, with the Euclidean smoothness
        // weighed x5 on glide slopes, a 0.7 m kernel and the glide in its gate; its 900 reserved iterations
        // take seed 1's stage 5 extension (600 iterations that handed over the same checkpoint) and leave
        // it its whole 925 after a sixth stage that stops at 251.
        let glide = c.stage_train_config(7).unwrap();
        assert_eq!(c.stages[6].validation, c.stages[5].validation, "judged on the sixth stage's validation set");
        assert_eq!(c.stages[6].gate, Gate { glide_fraction: Some(0.5), ..c.stages[5].gate.clone() });
        let (mut unglided, mut sixth) = (glide.task.clone(), manoeuvres.task.clone());
        (unglided.reward.position_scale_m, unglided.reward.smoothness_glide_gain) = (0.85, 0.0);
        sixth.reward.smoothness_glide_gain = 0.0;
        assert_eq!(unglided, sixth, "the sixth stage's task but for the kernel and the glide slopes' smoothness");
        assert_eq!((glide.task.reward.position_scale_m, glide.task.reward.smoothness_glide_gain), (0.7, 4.0));
        assert_eq!(glide.ppo.smoothness_norm, flapper_ppo::config::SmoothnessNorm::Euclidean);
        assert_eq!(c.extension_iterations(5, SEED1_BEFORE_STAGE5, 1200).unwrap(), 0);
        let seed1_before_glide = SEED1_BEFORE_STAGE5 + (1200 + 251) * 6144;
        assert_eq!(c.stage_iterations(7, seed1_before_glide).unwrap(), 925);
        check_budget(&c, "curriculum.toml");
    }

    /// Every config under configs/ reads: each curriculum (a file with `[[stages]]` or `extends`) builds
    /// every stage's `flapper train` config (the shipped ones within the paper's 30 M steps), each
    /// `flapper train` config loads, and each experiment has its line in configs/experiments/README.md.
    #[test]
    fn every_config_the_repository_holds_reads_and_each_experiment_is_listed() {
        let configs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../configs");
        let listed = std::fs::read_to_string(configs.join("experiments/README.md")).unwrap();
        let mut curricula = 0;
        for folder in [configs.clone(), configs.join("experiments")] {
            for entry in std::fs::read_dir(&folder).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_none_or(|e| e != "toml") {
                    continue;
                }
                let name = path.file_name().unwrap().to_string_lossy().into_owned();
                let text = std::fs::read_to_string(&path).unwrap();
                if text.lines().any(|l| l.starts_with("[[stages]]") || l.starts_with("extends")) {
                    let c = CurriculumConfig::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
                    for k in 1..=c.stages.len() {
                        c.stage_train_config(k).unwrap_or_else(|e| panic!("{name}, stage {k}: {e}"));
                    }
                    if folder == configs {
                        check_budget(&c, &name); // an experiment may spend more (curriculum-restart-stalled.toml)
                    }
                    curricula += 1;
                } else {
                    TrainConfig::load(&path, None).unwrap_or_else(|e| panic!("{name}: {e}"));
                }
                if folder.ends_with("experiments") {
                    assert!(
                        listed.contains(&format!("`{name}`")),
                        "{name} has no line in configs/experiments/README.md"
                    );
                }
            }
        }
        assert!(curricula >= 2, "the shipped curriculum and the transfer at least: {curricula}");
    }

    #[test]
    fn the_experiments_build_on_the_shipped_curriculum_and_read() {
        // configs/experiments/curriculum-*.toml extend configs/curriculum.toml (docs/experiments.md has
        // each one's section): stages 1-4 are the shipped ones by construction (each keeps the shipped
        // stages through the last one it ran on, `stages_through`), and each must still read and check
        // after any change to the curriculum it builds on.
        let seven = shipped("curriculum.toml");
        let five = CurriculumConfig { stages: seven.stages[..5].to_vec(), ..seven.clone() };
        let four = CurriculumConfig { stages: five.stages[..4].to_vec(), ..five.clone() };
        let flight_modes = shipped("experiments/curriculum-flight-modes.toml");
        assert_eq!(task_stages(&flight_modes), [1, 2, 3, 4, 4]);
        assert!(flight_modes.stages[..4] == four.stages[..] && flight_modes.max_env_steps == four.max_env_steps);
        let stage = flight_modes.stage_train_config(5).unwrap();
        assert!(stage.ppo.smoothness_coef > 0.0 && stage.task.reference.glide_probability > 0.0);
        assert!(flight_modes.stages[4].gate.identification_required, "the flight modes must keep the identified loop");
        check_budget(&flight_modes, "curriculum-flight-modes.toml");

        let slow = shipped("experiments/curriculum-slow-flight.toml");
        assert_eq!(task_stages(&slow), [1, 2, 3, 4, 4, 4]);
        let (level, priced) = (slow.stage_train_config(5).unwrap(), slow.stage_train_config(6).unwrap());
        assert!(level.task.reference.level_probability > 0.0 && priced.task.reference.level_probability > 0.0);
        assert_eq!(priced.ppo.smoothness_coef, 0.0, "the recipe without the smoothness term");
        assert_eq!(slow.stages[4].gate, Gate { min_iterations: 400, ..Gate::completing(50.0) }, "written whole");
        check_budget(&slow, "curriculum-slow-flight.toml");

        // The shipped curriculum with a 42 M budget, and the budget a restart has: after seed 2's stages 1-2
        // (227 iterations) and a stalled stage 3 (3200), 21.06 M steps, the shipped 30 M leave 1100 iterations
        // once stage 4 keeps the 300 it needs (stage 5, optional, keeps nothing); 42 M leave half the stage's
        // budget, 1600. Seed 3's stage 4, stalled at 1000 after 3103 iterations of stages 1-3, gets its half
        // budget, 500 (475 while stage 5 kept 300).
        let restart = shipped("experiments/curriculum-restart-stalled.toml");
        assert!(restart.stages == five.stages && restart.max_env_steps == Some(42_000_000), "the budget alone differs");
        // The restarts from the best checkpoint (#57, the narrow robot's stage 2): what stages 2-4 do once
        // stalled differs, nothing they train or how they are judged.
        let from_best = shipped("experiments/curriculum-restart-from-best.toml");
        let best: Vec<(Option<f32>, bool)> =
            from_best.stages.iter().map(|s| (s.restart_noise_std, s.restart_from_best)).collect();
        assert_eq!(best, [(None, false), (Some(0.4), true), (Some(0.4), true), (Some(0.4), true), (None, false)]);
        let trained = |c: &CurriculumConfig| c.stages.iter().map(StageConfig::as_trained).collect::<Vec<_>>();
        assert!(trained(&from_best) == trained(&five) && from_best.max_env_steps == five.max_env_steps);
        let seed2_before_stage3 = 227 * 6144;
        assert_eq!(five.extension_iterations(3, seed2_before_stage3, 3200).unwrap(), 1100);
        assert_eq!(restart.extension_iterations(3, seed2_before_stage3, 3200).unwrap(), 1600);
        assert_eq!(five.extension_iterations(4, 3103 * 6144, 1000).unwrap(), 500);
        // Not optional, stage 5 would keep its 300 from stage 3's restart.
        let mut required = five.clone();
        required.stages[4].optional = false;
        assert_eq!(required.extension_iterations(3, seed2_before_stage3, 3200).unwrap(), 800);
        // A stage 2 still improving at its 400th iteration (a heavier robot's, after 126 of stage 1) may
        // add half its budget: stages 3-5 keep 2000 + 300 + 300 iterations.
        assert_eq!(five.extension_iterations(2, 126 * 6144, 400).unwrap(), 200);

        // A later stage's reserved_iterations keep its budget from the extensions of the stages before it
        // (never from their own budgets). Seed 1's shipped stages 1-4 trained 2504 iterations and its stage
        // 5 its whole 1200 without the gate: stage 5 adds its half budget, 600, while an optional sixth
        // stage keeps nothing back, and the 7.24 M steps the run leaves go to the sixth stage (1175 of them
        // in whole validations of 25) when it reserves them; a reservation of 1100 leaves stage 5 one
        // validation interval more (50 of the 78 left).
        let slope_sixth = shipped("experiments/curriculum-glide-slope-stage.toml");
        assert_eq!(slope_sixth.extension_iterations(5, SEED1_BEFORE_STAGE5, 1200).unwrap(), 600, "nothing kept back");
        let mut reserving = slope_sixth.clone();
        reserving.stages[5].max_iterations = 1175;
        reserving.stages[5].reserved_iterations = Some(1175);
        assert_eq!(reserving.extension_iterations(5, SEED1_BEFORE_STAGE5, 1200).unwrap(), 0);
        assert_eq!(reserving.stage_iterations(5, SEED1_BEFORE_STAGE5).unwrap(), 1200, "its own budget is kept");
        assert_eq!(reserving.stage_iterations(6, SEED1_BEFORE_STAGE5 + 1200 * 6144).unwrap(), 1175);
        reserving.stages[5].reserved_iterations = Some(1100);
        assert_eq!(reserving.extension_iterations(5, SEED1_BEFORE_STAGE5, 1200).unwrap(), 50);
        // Against a required stage an optional one's reservation holds nothing back: seed 3's stage 4,
        // stalled at its 1000th iteration after 3103 of stages 1-3, restarts for its half budget, 500, with
        // the sixth stage reserving 1100 as without the reservation. Were the sixth stage required, its
        // reservation would hold: the 4103 iterations trained and its 1100 leave none of the 30 M.
        assert_eq!(reserving.extension_iterations(4, 3103 * 6144, 1000).unwrap(), 500);
        assert_eq!(slope_sixth.extension_iterations(4, 3103 * 6144, 1000).unwrap(), 500);
        let mut required_sixth = reserving.clone();
        required_sixth.stages[5].optional = false;
        assert_eq!(required_sixth.extension_iterations(4, 3103 * 6144, 1000).unwrap(), 0);
        let unreserved = StageConfig { reserved_iterations: None, ..reserving.stages[5].clone() };
        assert_eq!(unreserved.as_trained(), reserving.stages[5].as_trained(), "what it trains is the same");
        // The light twist's sixth stage (300 iterations reserved) leaves seed 1's stage 5 its 600-iteration
        // extension, so its first five stages train the shipped bits and the run stays within the 30 M.
        let light = shipped("experiments/curriculum-light-feathering-stage.toml");
        assert!(light.stages[..5] == five.stages[..] && light.max_env_steps == five.max_env_steps);
        assert_eq!(light.extension_iterations(5, SEED1_BEFORE_STAGE5, 1200).unwrap(), 600);
        assert_eq!(light.stage_iterations(6, SEED1_BEFORE_STAGE5 + 1800 * 6144).unwrap(), 300);
        let twisted = light.stage_train_config(6).unwrap();
        assert_eq!(twisted.task.control.passive_feathering_s, 0.01);
        assert_eq!(twisted.task.reference.loop_probability, 0.6);
        assert_eq!(twisted.ppo, light.stage_train_config(5).unwrap().ppo, "stage 5's learner settings");

        let oscillator = shipped("experiments/curriculum-oscillator.toml");
        assert_eq!(task_stages(&oscillator), [1, 2, 3, 3, 4]);
        let smoothness: Vec<f32> =
            (1..=5).map(|k| oscillator.stage_train_config(k).unwrap().ppo.smoothness_coef).collect();
        assert_eq!(smoothness, [0.3, 0.3, 0.0, 0.0, 0.03]);
        let restarted = oscillator.stage_train_config(4).unwrap();
        assert_eq!(restarted.runner.init_from_noise_std, Some(0.4), "the noise restarted");
        assert_eq!(restarted.task.control.action_mode, flapper_task::config::ActionMode::FlapOscillator);
        assert_eq!(oscillator.stages[3].validation, oscillator.stages[2].validation, "stage 3's, copied");

        // The curriculum before stage 3's episodes started along their paths: stage 3 alone differs.
        let without = shipped("experiments/curriculum-without-path-starts.toml");
        assert_eq!(path_start_probabilities(&without), [0.0; 5]);
        assert!(without.stages.iter().zip(&five.stages).enumerate().all(|(k, (a, b))| (k == 2) != (a == b)));
        assert_eq!(without.max_env_steps, five.max_env_steps);
        check_budget(&without, "curriculum-without-path-starts.toml");

        // A controller fine-tuned on one's own robot: the shipped stages 4 and 5 alone, unchanged.
        let transfer = shipped("curriculum-transfer.toml");
        // Stages 4 and 5 as shipped, but stage 4 seeks its randomized entries (decided at its budget's end).
        assert_eq!(transfer.stages[1], five.stages[4], "stage 5 as shipped");
        let stage_4 = &transfer.stages[0];
        assert!(stage_4.gate.randomized_sought);
        assert_eq!(stage_4.gate, Gate { randomized_sought: true, ..five.stages[3].gate.clone() });
        assert_eq!(StageConfig { gate: five.stages[3].gate.clone(), ..stage_4.clone() }, five.stages[3]);
        assert_eq!(stage_4.as_trained(), five.stages[3].as_trained(), "stage 4 trains as shipped");
        assert_eq!(transfer.max_env_steps, five.max_env_steps);
        check_budget(&transfer, "curriculum-transfer.toml");

        // CAPS's Euclidean smoothness in the efficient stage: alone from a controller (E3, E6), in the whole
        // curriculum lifted in manoeuvres (E6t), and gF's recipe (weighed on glide slopes, the noise restarted
        // low) alone and as a sixth stage after the shipped five, which stay as they are (stages 5 and 6 both
        // optional: a missed stage 5 ends the run with stage 4's controller); each stage asks the glide
        // besides its bars.
        use flapper_ppo::config::SmoothnessNorm;
        let alone = shipped("experiments/curriculum-euclidean-smoothness.toml");
        assert_eq!(alone.stages.len(), 1);
        assert!(!alone.stages[0].optional, "the only stage cannot be optional");
        let turns = shipped("experiments/curriculum-euclidean-smoothness-turns.toml");
        let slopes = shipped("experiments/curriculum-euclidean-glide-slopes.toml");
        let sixth = shipped("experiments/curriculum-glide-stage.toml");
        for config in [&turns, &sixth] {
            assert!(config.stages[..4] == five.stages[..4] && config.max_env_steps == five.max_env_steps);
        }
        assert_eq!(sixth.stages[4], five.stages[4]);
        assert!(sixth.stages[5].optional && sixth.stages[5].name == "glide");
        for (config, k) in [(&alone, 1), (&turns, 5), (&slopes, 1), (&sixth, 6)] {
            let stage = config.stage_train_config(k).unwrap();
            assert_eq!(stage.ppo.smoothness_norm, SmoothnessNorm::Euclidean);
            assert_eq!(stage.ppo.desired_kl, 0.005, "the shipped stage's other settings kept");
            assert_eq!(config.stages[k - 1].gate.glide_fraction, Some(0.5));
        }
        assert_eq!(turns.stage_train_config(5).unwrap().task.reward.smoothness_turn_scale_degps, 60.0);
        check_budget(&turns, "curriculum-euclidean-smoothness-turns.toml");
        for (config, k) in [(&slopes, 1), (&sixth, 6)] {
            let stage = config.stage_train_config(k).unwrap();
            assert_eq!(stage.ppo.smoothness_coef, 0.03);
            assert_eq!(stage.task.reward.smoothness_glide_gain, 9.0);
            assert_eq!(config.stages[k - 1].start_noise_std, Some(0.25), "the noise restarted low");
        }
        check_budget(&sixth, "curriculum-glide-stage.toml");

        // gS: the price on glide slopes only (a tenth of gF's everywhere, x100 on glide slopes: the same
        // 0.3 there), validated every 25, alone and as the sixth stage.
        let slope_only = shipped("experiments/curriculum-glide-slope-smoothness.toml");
        let slope_stage = shipped("experiments/curriculum-glide-slope-stage.toml");
        assert!(slope_stage.stages[..5] == five.stages[..] && slope_stage.max_env_steps == five.max_env_steps);
        assert!(slope_stage.stages[4].optional && slope_stage.stages[5].optional, "both refinements optional");
        for (config, k) in [(&slope_only, 1), (&slope_stage, 6)] {
            let stage = config.stage_train_config(k).unwrap();
            assert_eq!(stage.ppo.smoothness_norm, SmoothnessNorm::Euclidean);
            assert_eq!(stage.ppo.smoothness_coef, 0.003);
            assert_eq!(stage.task.reward.smoothness_glide_gain, 99.0);
            let on_glide_slopes =
                f64::from(stage.ppo.smoothness_coef) * (1.0 + stage.task.reward.smoothness_glide_gain);
            assert!((on_glide_slopes - 0.3).abs() < 1e-6, "gF's price on glide slopes: {on_glide_slopes}");
            assert_eq!(config.stages[k - 1].validate_every, 25);
            assert_eq!(config.stages[k - 1].start_noise_std, Some(0.25));
            assert_eq!(config.stages[k - 1].gate.glide_fraction, Some(0.5));
        }
        assert_eq!(slope_only.stages[0].max_iterations, slopes.stages[0].max_iterations);
        check_budget(&slope_stage, "curriculum-glide-slope-stage.toml");

        // gM3: gS's price on the flaps alone, three times as hard; everything else gS's.
        let flaps = shipped("experiments/curriculum-glide-slope-flaps.toml");
        let (stage, gs) = (flaps.stage_train_config(1).unwrap(), slope_only.stage_train_config(1).unwrap());
        assert_eq!(stage.ppo.smoothness_action_scale, [3.0, 0.0, 3.0, 0.0, 0.0]);
        assert_eq!(flaps.stages[0].max_iterations, 500);
        let ppo = flapper_ppo::PpoConfig { smoothness_action_scale: Vec::new(), ..stage.ppo.clone() };
        assert!(ppo == gs.ppo && stage.task == gs.task, "only the shares differ from gS");
        let flaps_stage = shipped("experiments/curriculum-glide-slope-flaps-stage.toml");
        let (sixth, gs_sixth) =
            (flaps_stage.stage_train_config(6).unwrap(), slope_stage.stage_train_config(6).unwrap());
        assert_eq!(sixth.ppo.smoothness_action_scale, [2.0, 0.0, 2.0, 0.0, 0.0]);
        assert!(flaps_stage.stages[..5] == slope_stage.stages[..5] && sixth.task == gs_sixth.task);
        check_budget(&flaps_stage, "curriculum-glide-slope-flaps-stage.toml");

        // h575: sixF2's stage with the price on a flap faster than 5.75 Hz; nothing else changed.
        let flap_rate = shipped("experiments/curriculum-flap-rate-stage.toml");
        let priced = flap_rate.stage_train_config(6).unwrap();
        assert_eq!((priced.task.reward.flap_rate_weight, priced.task.reward.flap_max_hz), (0.1, 5.75));
        let unpriced = flapper_task::config::RewardConfig {
            flap_rate_weight: 0.0,
            flap_max_hz: sixth.task.reward.flap_max_hz,
            ..priced.task.reward.clone()
        };
        assert!(unpriced == sixth.task.reward && priced.ppo == sixth.ppo, "only the flap's price differs");
        assert!(flap_rate.stages[..5] == flaps_stage.stages[..5]);
        check_budget(&flap_rate, "curriculum-flap-rate-stage.toml");

        // gz30: h575's stage with the held wing paid on glide slopes; nothing else changed.
        let glide_hold = shipped("experiments/curriculum-glide-hold-stage.toml");
        let paid = glide_hold.stage_train_config(6).unwrap();
        assert_eq!((paid.task.reward.glide_hold_weight, paid.task.reward.glide_hold_scale_deg), (0.5, 30.0));
        let unpaid = flapper_task::config::RewardConfig {
            glide_hold_weight: 0.0,
            glide_hold_scale_deg: priced.task.reward.glide_hold_scale_deg,
            ..paid.task.reward.clone()
        };
        assert!(unpaid == priced.task.reward && paid.ppo == priced.ppo, "only the glide's pay differs");
        assert!(glide_hold.stages[..5] == flap_rate.stages[..5]);
        check_budget(&glide_hold, "curriculum-glide-hold-stage.toml");

        // cks: gz30's curriculum with a 5.3 Hz clock in every stage's observation; nothing else changed.
        use flapper_task::config::{ObservationConfig, TaskConfig};
        let clock = shipped("experiments/curriculum-clock.toml");
        for (number, unclocked) in (1..=6).zip(&glide_hold.stages) {
            let clocked = clock.stage_train_config(number).unwrap();
            assert_eq!(clocked.task.observation.clock_hz, 5.3, "stage {number}");
            let without = TrainConfig {
                task: TaskConfig {
                    observation: ObservationConfig { clock_hz: 0.0, ..clocked.task.observation.clone() },
                    ..clocked.task.clone()
                },
                ..clocked
            };
            assert_eq!(without, glide_hold.stage_train_config(number).unwrap(), "stage {number} ({})", unclocked.name);
        }
        check_budget(&clock, "curriculum-clock.toml");

        // gF's sixth stage keeping the budget stage 5's extension spent: the same stages but for the glide
        // stage's budget, its reservation and its validation interval.
        let reserved = shipped("experiments/curriculum-glide-stage-reserved.toml");
        let gf_sixth = shipped("experiments/curriculum-glide-stage.toml");
        assert!(reserved.stages[..5] == gf_sixth.stages[..5] && reserved.max_env_steps == gf_sixth.max_env_steps);
        let glide = &reserved.stages[5];
        assert_eq!((glide.max_iterations, glide.reserved_iterations, glide.validate_every), (1175, Some(1175), 25));
        assert_eq!(reserved.stage_train_config(6).unwrap().task, gf_sixth.stage_train_config(6).unwrap().task);
        assert_eq!(reserved.extension_iterations(5, 2504 * 6144, 1200).unwrap(), 0, "seed 1's stage 5 is not extended");
        check_budget(&reserved, "curriculum-glide-stage-reserved.toml");
    }

    /// Writes `files` (name, text) into a fresh folder and returns it.
    fn folder(name: &str, files: &[(&str, &str)]) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("flapper-extends-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("experiments")).unwrap();
        for (file, text) in files {
            std::fs::write(dir.join(file), text).unwrap();
        }
        dir
    }

    #[test]
    fn a_file_extending_another_changes_appends_copies_and_inserts_stages_by_name() {
        let overlay = r#"
extends = "../base.toml"
seed = 5
runner = { threads = 2 }
[[stages]]
modify = "climb and dive"
max_iterations = 6
task.reward = { energy_scale_w = 15.0 }
[[stages]]
name = "first again"
from = "cruise"
after = "cruise"
validation = { references = ["lateral"], episodes = 1 }
[[stages]]
name = "last"
validate_every = 1
max_iterations = 1
validation = { references = ["loop"], episodes = 1 }
gate = { completed_percent = 0 }
task = { stage = 3 }
"#;
        let dir = folder("merge", &[("base.toml", TINY), ("experiments/more.toml", overlay)]);
        let c = CurriculumConfig::load(&dir.join("experiments/more.toml")).unwrap();
        let base = CurriculumConfig::from_toml(TINY, "base").unwrap();
        let names: Vec<&str> = c.stages.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["cruise", "first again", "climb and dive", "last"]);
        assert_eq!(c.seed, 5, "a top-level key replaced");
        let first = c.stage_train_config(1).unwrap();
        assert_eq!((first.runner.envs, first.runner.threads), (4, 2), "[runner] merged key by key");
        let copy = &c.stages[1];
        assert_eq!(copy.validation.references, ["lateral"], "a list replaced whole");
        assert_eq!((copy.max_iterations, &copy.gate, &copy.task), (4, &base.stages[0].gate, &base.stages[0].task));
        let changed = &c.stages[2];
        assert_eq!((changed.max_iterations, changed.validate_every), (6, 1), "changed in place, the rest kept");
        let reward = c.stage_train_config(3).unwrap().task.reward;
        assert_eq!(reward.energy_scale_w, 15.0);
        assert_eq!(c.stages[3].task.get("stage").and_then(toml::Value::as_integer), Some(3));
        // A file may extend one that extends another; what a run saves is the whole curriculum.
        std::fs::write(dir.join("experiments/again.toml"), "extends = \"more.toml\"\nseed = 6\n").unwrap();
        let again = CurriculumConfig::load(&dir.join("experiments/again.toml")).unwrap();
        assert_eq!(again, CurriculumConfig { seed: 6, ..c.clone() });
        assert!(!again.to_toml().contains("extends"));
        assert_eq!(CurriculumConfig::from_toml(&again.to_toml(), "saved").unwrap(), again);
        // A stage of the base left out by name; the rest as they were.
        let fewer = "extends = \"more.toml\"\n[[stages]]\nremove = \"first again\"\n";
        std::fs::write(dir.join("experiments/fewer.toml"), fewer).unwrap();
        let fewer = CurriculumConfig::load(&dir.join("experiments/fewer.toml")).unwrap();
        let names: Vec<&str> = fewer.stages.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["cruise", "climb and dive", "last"]);
        assert!(fewer.stages[1] == c.stages[2] && fewer.stages[2] == c.stages[3]);
        // The base's stages through one of them: a stage the base gains later stays out of the
        // experiment, and the entries apply to what is kept.
        let through = "extends = \"more.toml\"\nstages_through = \"first again\"\n[[stages]]\nmodify = \"cruise\"\nmax_iterations = 9\n";
        std::fs::write(dir.join("experiments/through.toml"), through).unwrap();
        let through = CurriculumConfig::load(&dir.join("experiments/through.toml")).unwrap();
        let names: Vec<&str> = through.stages.iter().map(|s| s.name.as_str()).collect();
        assert_eq!(names, ["cruise", "first again"]);
        assert_eq!((through.stages[0].max_iterations, &through.stages[1]), (9, &c.stages[1]));
        assert!(!through.to_toml().contains("stages_through"), "a run saves the stages, not the key");
    }

    #[test]
    fn a_missing_base_or_stage_is_refused_in_one_line_naming_the_file_and_what_is_missing() {
        let refused = |name: &str, overlay: &str| {
            let dir = folder(name, &[("base.toml", TINY), ("experiments/x.toml", overlay)]);
            let message = CurriculumConfig::load(&dir.join("experiments/x.toml")).unwrap_err().to_string();
            assert!(message.contains("x.toml") && !message.contains('\n'), "{message}");
            message
        };
        let e = refused("missing", "extends = \"../nowhere.toml\"\n");
        assert!(e.contains("extends '../nowhere.toml'") && e.contains("cannot be read"), "{e}");
        for key in ["modify", "from", "after", "remove"] {
            let entry = match key {
                "modify" | "remove" => format!("{key} = \"crusie\""),
                _ => format!("name = \"new\"\n{key} = \"crusie\""),
            };
            let e = refused(key, &format!("extends = \"../base.toml\"\n[[stages]]\n{entry}\n"));
            assert!(e.contains(&format!("{key} = 'crusie' names no stage of '../base.toml'")), "{e}");
            assert!(e.contains("'cruise', 'climb and dive'"), "the stages there are listed: {e}");
        }
        let e = refused("twice", "extends = \"../base.toml\"\n[[stages]]\nname = \"cruise\"\nmax_iterations = 2\n");
        assert!(e.contains("'cruise'") && e.contains("modify = 'cruise'"), "{e}");
        let e = refused("nameless", "extends = \"../base.toml\"\n[[stages]]\nmax_iterations = 2\n");
        assert!(e.contains("entry 1") && e.contains("modify") && e.contains("name"), "{e}");
        let e =
            refused("in-place", "extends = \"../base.toml\"\n[[stages]]\nmodify = \"cruise\"\nafter = \"cruise\"\n");
        assert!(e.contains("in place"), "{e}");
        let e =
            refused("remove-more", "extends = \"../base.toml\"\n[[stages]]\nremove = \"cruise\"\nmax_iterations = 2\n");
        assert!(e.contains("remove = 'cruise'") && e.contains("no other key"), "{e}");
        let dir = folder(
            "bad-base",
            &[("base.toml", "stages = 5\n"), ("experiments/x.toml", "extends = \"../base.toml\"\n")],
        );
        let e = CurriculumConfig::load(&dir.join("experiments/x.toml")).unwrap_err().to_string();
        assert!(e.contains("base.toml': stages must be a list of [[stages]] tables, got 5"), "{e}");
        let e = refused("through", "extends = \"../base.toml\"\nstages_through = \"crusie\"\n");
        assert!(e.contains("x.toml': stages_through = 'crusie' names no stage of '../base.toml'"), "{e}");
        assert!(e.contains("'cruise', 'climb and dive'") && !e.contains("entry"), "{e}");
        let e = refused("through-number", "extends = \"../base.toml\"\nstages_through = 2\n");
        assert!(e.contains("stages_through must be a stage name, got 2"), "{e}");
        let e = refused("circle", "extends = \"x.toml\"\n");
        assert!(e.contains("extends 'x.toml', which extends it again"), "{e}");
        let e =
            refused("checked", "extends = \"../base.toml\"\n[[stages]]\nmodify = \"cruise\"\nvalidate_every = 50\n");
        assert!(e.contains("stage 1 ('cruise')") && e.contains("validate_every (50)"), "the result is checked: {e}");
    }

    #[test]
    fn mistakes_anywhere_are_refused_before_training_naming_the_stage() {
        let err = |from: &str, to: &str| {
            let text = TINY.replacen(from, to, 1);
            assert_ne!(text, TINY, "the test edits the config");
            CurriculumConfig::from_toml(&text, "bad.toml").unwrap_err().to_string()
        };
        let e = err("task = { stage = 2 }", "task = { stage = 2, reward = { energy_wieght = 1 } }");
        assert!(e.contains("bad.toml") && e.contains("stage 2") && e.contains("energy_wieght"), "{e}");
        let e = err("validate_every = 1", "validate_every = 5");
        assert!(e.contains("stage 2") && e.contains("validate_every"), "{e}");
        let e = err("completed_percent = 0 }", "completed_percent = 120 }");
        assert!(e.contains("completed_percent") && e.contains("120"), "{e}");
        let e = err("episodes = 1 }", "episodes = 0 }");
        assert!(e.contains("episodes"), "{e}");
        let e = err("start_noise_std = 0.4", "start_noise_std = -1");
        assert!(e.contains("start_noise_std"), "{e}");
        for bad in ["0", "-0.4", "11", "nan"] {
            let e = err("start_noise_std = 0.4", &format!("start_noise_std = 0.4\nrestart_noise_std = {bad}"));
            assert!(e.contains("restart_noise_std must be in (0, 10]"), "{bad}: {e}");
        }
        let e = err("start_noise_std = 0.4", "start_noise_std = 0.4\nrestart_from_best = true");
        assert!(e.contains("restart_from_best = true needs restart_noise_std"), "{e}");
        for count in [0, MAX_AVERAGED_CHECKPOINTS + 1] {
            let e = err("start_noise_std = 0.4", &format!("start_noise_std = 0.4\naverage_checkpoints = {count}"));
            assert!(
                e.contains("stage 2") && e.contains("average_checkpoints") && e.contains(&count.to_string()),
                "{e}"
            );
        }
        // Stage 2 (required, max_iterations 2, least 1) keeps back 1 or 2; more than its budget, or less than
        // it needs to hand over, is refused.
        for reserved in [0, 3] {
            let e = err("start_noise_std = 0.4", &format!("start_noise_std = 0.4\nreserved_iterations = {reserved}"));
            assert!(
                e.contains("stage 2") && e.contains(&format!("reserved_iterations must be in [1, 2], got {reserved}")),
                "{e}"
            );
        }
        let e = err("[ppo]\nsteps_per_env = 8", "[ppo]\nsteps_per_env = 0");
        assert!(e.contains("ppo.steps_per_env"), "{e}");
        let e = err("seed = 3", "seed = 3\nstagez = 1");
        assert!(e.contains("stagez"), "{e}");
        let randomized = |setting: &str| {
            format!(
                "validation = {{ references = [\"cruise\"], episodes = 1, randomized = [{setting}] }}\ngate = {{ completed_percent = 0 }}\ntask = {{ stage = 1 }}"
            )
        };
        let first = "validation = { references = [\"cruise\"], episodes = 1 }\ngate = { completed_percent = 0 }\ntask = { stage = 1 }";
        let good = randomized(
            r#"{ name = "fluid", references = ["lateral"], episodes = 2, randomization = { fluid_coefficient_scale = [0.7, 1.3] } }"#,
        );
        let c = CurriculumConfig::from_toml(&TINY.replacen(first, &good, 1), "ok.toml").unwrap();
        let setting = &c.stages[0].validation.randomized[0];
        assert!(setting.flown_randomization().enabled, "a randomized validation is always randomized");
        assert_eq!(setting.flown_randomization().fluid_coefficient_scale, [0.7, 1.3]);
        assert_eq!(CurriculumConfig::from_toml(&c.to_toml(), "saved").unwrap(), c);
        let e = err(
            first,
            &randomized(
                r#"{ name = "fluid", references = ["lateral"], episodes = 2, randomization = { fluid_coefficient_scale = [1.3, 0.7] } }"#,
            ),
        );
        assert!(e.contains("stage 1") && e.contains("'fluid'") && e.contains("fluid_coefficient_scale"), "{e}");
        let e = err(first, &randomized(r#"{ name = "a b", references = ["lateral"], episodes = 2 }"#));
        assert!(e.contains("'a b'") && e.contains("name"), "{e}");
        let e = err(first, &randomized(r#"{ name = "t3", references = [], episodes = 2 }"#));
        assert!(e.contains("'t3'") && e.contains("reference"), "{e}");
        let e = err("completed_percent = 0 }", "completed_percent = 0, randomized_completed_percent = 101 }");
        assert!(e.contains("randomized_completed_percent") && e.contains("101"), "{e}");
        let e = err("completed_percent = 0 }", "completed_percent = 0, identification_fit_percent = -5 }");
        assert!(e.contains("identification_fit_percent") && e.contains("-5"), "{e}");
        let e = err("completed_percent = 0 }", "completed_percent = 0, glide_fraction = 1.5 }");
        assert!(e.contains("gate.glide_fraction") && e.contains("1.5"), "{e}");
        let e = err("completed_percent = 0 }", "completed_percent = 0, max_energy_ratio = -1.0 }");
        assert!(e.contains("gate.max_energy_ratio") && e.contains("-1"), "{e}");
        let e = err("completed_percent = 0 }", "completed_percent = 0, cruise_flap_hz = [6.0, 4.0] }");
        assert!(e.contains("gate.cruise_flap_hz") && e.contains("[6, 4]"), "{e}");
        let e = err("completed_percent = 0 }", "completed_percent = 0, cruise_flap_flight = \"cruise\" }");
        assert!(e.contains("cruise_flap_flight") || e.contains("cruise_reference"), "{e}");
        let asked = "completed_percent = 0, cruise_flap_hz = [4.0, 6.0], cruise_flap_flight = \"cruise_reference\" }";
        let c = CurriculumConfig::from_toml(&TINY.replacen("completed_percent = 0 }", asked, 1), "ok.toml").unwrap();
        assert_eq!(c.stages[0].gate.cruise_flap_flight, CruiseFlapFlight::CruiseReference);
        assert!(c.to_toml().contains("cruise_flap_flight = \"cruise_reference\""));
        assert_eq!(CurriculumConfig::from_toml(&c.to_toml(), "saved").unwrap(), c);
        let starts = "completed_percent = 0, cruise_flap_hz = [4.0, 6.0], cruise_flap_flight = \"validation_starts\" }";
        let c = CurriculumConfig::from_toml(&TINY.replacen("completed_percent = 0 }", starts, 1), "ok.toml").unwrap();
        assert_eq!(c.stages[0].gate.cruise_flap_flight, CruiseFlapFlight::ValidationStarts);
        assert_eq!(CurriculumConfig::from_toml(&c.to_toml(), "saved").unwrap(), c);
        let no_cruise =
            TINY.replacen("references = [\"cruise\"], episodes = 1 }", "references = [\"lateral\"], episodes = 1 }", 1);
        assert_ne!(no_cruise, TINY, "the test flies no cruise in stage 1");
        let e = CurriculumConfig::from_toml(&no_cruise.replacen("completed_percent = 0 }", starts, 1), "bad.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("stage 1") && e.contains("validation_starts") && e.contains("lateral"), "{e}");
        let plain = CurriculumConfig::from_toml(TINY, "ok.toml").unwrap();
        assert_eq!(plain.stages[0].gate.cruise_flap_flight, CruiseFlapFlight::LongitudinalSegment);
        assert!(
            !plain.to_toml().contains("cruise_flap_flight"),
            "the default is not written: old folders compare equal"
        );
        let e = err("completed_percent = 0 }", "completed_percent = 0, identification_required = true }");
        assert!(e.contains("identification_required") && e.contains("identification_fit_percent"), "{e}");
        let second = "validation = { references = [\"longitudinal\"], procedural = 1, episodes = 1 }";
        let e = err(
            second,
            "validation = { references = [\"longitudinal\"], episodes = 1, reference_episodes = { loop = 5 } }",
        );
        assert!(e.contains("stage 2") && e.contains("'loop'") && e.contains("longitudinal"), "{e}");
        let e = err(
            second,
            "validation = { references = [\"longitudinal\"], episodes = 1, reference_episodes = { longitudinal = 0 } }",
        );
        assert!(e.contains("'longitudinal'") && e.contains("episodes > 0"), "{e}");
        let e = err("max_rms_m = 100.0 }", "max_rms_m = 100.0, reference_max_rms_m = { lateral = 0.3 } }");
        assert!(e.contains("stage 2") && e.contains("'lateral'") && e.contains("not a validation entry"), "{e}");
        let e = err("max_rms_m = 100.0 }", "max_rms_m = 100.0, reference_max_rms_m = { longitudinal = -0.3 } }");
        assert!(e.contains("'longitudinal'") && e.contains("-0.3"), "{e}");
        let e = err("max_rms_m = 100.0 }", "max_rms_m = 100.0, reference_max_energy_ratio = { immelmann = 3.0 } }");
        assert!(e.contains("stage 2") && e.contains("'immelmann'") && e.contains("not a validation entry"), "{e}");
        let e = err("max_rms_m = 100.0 }", "max_rms_m = 100.0, reference_max_energy_ratio = { longitudinal = 0.0 } }");
        assert!(e.contains("reference_max_energy_ratio") && e.contains("positive ratio"), "{e}");
        let priced = TINY.replacen(
            "max_rms_m = 100.0 }",
            "max_rms_m = 100.0, reference_max_energy_ratio = { longitudinal = 1.5 } }",
            1,
        );
        let c = CurriculumConfig::from_toml(&priced, "own.toml").unwrap();
        assert_eq!(c.stages[1].gate.reference_max_energy_ratio.get("longitudinal"), Some(&1.5));
        assert_eq!(CurriculumConfig::from_toml(&c.to_toml(), "saved").unwrap(), c, "the saved run reads back");
    }

    #[test]
    fn some_references_can_have_their_own_starts_and_rms_bars() {
        let text = TINY
            .replacen(
                "validation = { references = [\"longitudinal\"], procedural = 1, episodes = 1 }",
                "validation = { references = [\"cruise\", \"longitudinal\"], procedural = 1, episodes = 2, \
                 reference_episodes = { longitudinal = 5 } }",
                1,
            )
            .replacen("max_rms_m = 100.0 }", "max_rms_m = 100.0, reference_max_rms_m = { longitudinal = 0.3 } }", 1);
        let c = CurriculumConfig::from_toml(&text, "own.toml").unwrap();
        assert_eq!(c.stages[1].gate.reference_max_rms_m.get("longitudinal"), Some(&0.3));
        assert_eq!(CurriculumConfig::from_toml(&c.to_toml(), "saved").unwrap(), c, "the saved run reads back");
        let task = c.stage_train_config(2).unwrap().task;
        let set = crate::validation::ValidationSet::new(&c.stages[1].validation, &task, 0.004, 7).unwrap();
        let starts: Vec<(String, usize)> = set.entries.iter().map(|e| (e.name.clone(), e.episodes)).collect();
        let expected = [("cruise", 2), ("longitudinal", 5), ("procedural-1", 2)].map(|(n, k)| (n.to_owned(), k));
        assert_eq!(starts, expected, "longitudinal from its own 5 starts, the rest from the stage's 2");
        let plain = CurriculumConfig::from_toml(TINY, "tiny.toml").unwrap();
        assert!(!plain.to_toml().contains("reference_"), "runs saved without the new keys read as before");
    }
}
