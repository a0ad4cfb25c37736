//! Judging a checkpoint: fly a stage's validation set (named or CSV references and procedural ones,
//! from randomized starts drawn with the validation seed, and optionally some of them again under a
//! randomization of the dynamics and the wind) with the policy's mean action, and score it: completion
//! first, then RMS error. Flights use the CPU-independent inference path, so a checkpoint's
//! score is the same on every machine and when it is judged again after an interruption.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use flapper_analysis::frontier;
use flapper_eval::tracking::{
    EpisodeResult, TrackingController, evaluate_tracking, evaluate_tracking_randomized, mean_energy_per_metre_j,
};
use flapper_eval::tracking_report::{ANALYSED_JOINTS, TrackingSummary};
use flapper_eval::{PolicyFileError, ScriptedGaitConfig, load_flight_policy};
use flapper_sim::{ModelError, RobotModel};
use flapper_task::TaskConfig;
use flapper_task::config::RandomizationConfig;
use flapper_task::reference::generator::procedural;
use flapper_task::reference::{Reference, ReferenceError, resolve};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::config::{Gate, RANDOMIZED_SEPARATOR, ValidationConfig};

#[derive(Debug, thiserror::Error)]
pub enum ValidationError {
    #[error(transparent)]
    Policy(#[from] PolicyFileError),
    #[error("validation reference: {0}")]
    Reference(#[from] ReferenceError),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("identification: {0}")]
    Identification(String),
    #[error("flight modes: {0}")]
    FlightModes(String),
}

/// Where the left flap sits among `flapper eval`'s analysed joints.
const FLAP_LEFT: usize = 0;
const _: () = assert!(matches!(ANALYSED_JOINTS[FLAP_LEFT], flapper_sim::ActuatedJoint::FlapLeft));

/// How the drawn references of a validation set are named: `procedural-1`, `procedural-2`, ...
pub const PROCEDURAL_PREFIX: &str = "procedural-";

/// One line of a validation set: a reference, flown from `episodes` starts, nominal or randomized.
pub struct ValidationEntry {
    pub name: String,
    pub reference: Arc<Reference>,
    pub episodes: usize,
    pub randomization: Option<RandomizationConfig>,
}

/// The references of a validation set, built once per stage.
pub struct ValidationSet {
    pub entries: Vec<ValidationEntry>,
    pub seed: u64,
    /// The scripted gait's energy per metre (J/m, the mean over the entry's episodes) on the entries whose
    /// energy is priced ([`Self::price_energy`]), by entry name: what a checkpoint's is divided by.
    scripted_energy_per_metre_j: BTreeMap<String, f64>,
    /// The entry whose flap frequency [`Self::judge`] reads ([`Self::read_flap_on`]).
    flap_entry: Option<String>,
}

impl ValidationSet {
    /// `task` is the stage's: its control period, lookahead and procedural ranges.
    pub fn new(
        config: &ValidationConfig,
        task: &TaskConfig,
        timestep_s: f64,
        seed: u64,
    ) -> Result<Self, ValidationError> {
        let dt_s = task.control_period_s(timestep_s);
        let lookahead = task.observation.lookahead_steps;
        let mut references = Vec::new();
        for name in &config.references {
            references.push(Arc::new(resolve(name, dt_s, lookahead)?));
        }
        let mut randomized = Vec::new();
        for setting in &config.randomized {
            for name in &setting.references {
                let reference = Arc::new(resolve(name, dt_s, lookahead)?);
                randomized.push(ValidationEntry {
                    name: setting.entry_name(reference.name()),
                    reference,
                    episodes: setting.episodes,
                    randomization: Some(setting.flown_randomization()),
                });
            }
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let duration_s = task.episode.max_steps as f64 * dt_s;
        for k in 0..config.procedural {
            let drawn = procedural(&task.reference, duration_s, (lookahead + 1) as f64 * dt_s, dt_s, &mut rng);
            references.push(Arc::new(Reference::new(
                format!("{PROCEDURAL_PREFIX}{}", k + 1),
                drawn.dt_s(),
                drawn.points().to_vec(),
            )));
        }
        let nominal = references.into_iter().map(|reference| ValidationEntry {
            name: reference.name().to_owned(),
            episodes: config.episodes_of(reference.name()),
            reference,
            randomization: None,
        });
        Ok(Self {
            entries: nominal.chain(randomized).collect(),
            seed,
            scripted_energy_per_metre_j: BTreeMap::new(),
            flap_entry: None,
        })
    }

    /// Flies the scripted gait on `names`' entries from the same starts as every checkpoint will, so that
    /// [`Self::judge`] gives each of them its energy ratio: `flapper eval`'s, the mean energy per metre
    /// over the episodes, the checkpoint's over the scripted gait's flown with the default task as the
    /// evaluation flies it.
    pub fn price_energy<'a>(
        mut self,
        robot: &RobotModel,
        names: impl IntoIterator<Item = &'a String>,
    ) -> Result<Self, ValidationError> {
        let scripted = TrackingController::Scripted(ScriptedGaitConfig::default());
        let task = TaskConfig::default();
        let period_s = task.control_period_s(robot.timestep_s());
        for name in names {
            let entry = self.entries.iter().find(|e| &e.name == name).ok_or_else(|| {
                ValidationError::FlightModes(format!("'{name}' is not an entry of the validation set"))
            })?;
            let results = self.fly(robot, &scripted, &task, entry)?;
            self.scripted_energy_per_metre_j.insert(name.clone(), mean_energy_per_metre_j(&results, period_s));
        }
        Ok(self)
    }

    /// Has [`Self::judge`] read the flap's fundamental on entry `name` (where given): each start's after
    /// its first second, averaged over the starts as `flapper eval`'s table averages them.
    pub fn read_flap_on(mut self, name: Option<&str>) -> Result<Self, ValidationError> {
        if let Some(name) = name {
            if !self.entries.iter().any(|e| e.name == name) {
                return Err(ValidationError::FlightModes(format!(
                    "the flap frequency is read on '{name}', which is not an entry of the validation set"
                )));
            }
            self.flap_entry = Some(name.to_owned());
        }
        Ok(self)
    }

    fn fly(
        &self,
        robot: &RobotModel,
        controller: &TrackingController,
        task: &TaskConfig,
        entry: &ValidationEntry,
    ) -> Result<Vec<EpisodeResult>, ModelError> {
        let (reference, episodes) = (entry.reference.clone(), entry.episodes);
        match &entry.randomization {
            None => evaluate_tracking(robot, controller, task, reference, episodes, self.seed),
            Some(randomization) => {
                evaluate_tracking_randomized(robot, controller, task, randomization, reference, episodes, self.seed)
            }
        }
    }

    pub fn names(&self) -> Vec<String> {
        self.entries.iter().map(|e| e.name.clone()).collect()
    }

    /// Flies every entry from its randomized starts with the policy in `policy_path`.
    pub fn judge(&self, robot: &RobotModel, policy_path: &Path) -> Result<Score, ValidationError> {
        let (policy, task) = load_flight_policy(policy_path)?;
        let controller = TrackingController::Policy(Arc::new(policy));
        let period_s = task.control_period_s(robot.timestep_s());
        let mut per_reference = Vec::new();
        for entry in &self.entries {
            let results = self.fly(robot, &controller, &task, entry)?;
            let mut score = ReferenceScore::of(&entry.name, &results);
            if let Some(&scripted) = self.scripted_energy_per_metre_j.get(&entry.name) {
                // NaN (no bar met) where the scripted gait flew no energy.
                let own = mean_energy_per_metre_j(&results, period_s);
                score.energy_ratio = Some(frontier::energy_ratio(own, scripted).unwrap_or(f64::NAN));
            }
            if self.flap_entry.as_ref() == Some(&entry.name) {
                score.flap_hz = Some(TrackingSummary::of(&results, period_s, None).frequency_hz[FLAP_LEFT]);
            }
            per_reference.push(score);
        }
        Ok(Score::of(per_reference))
    }
}

/// One reference's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceScore {
    pub name: String,
    pub completed: usize,
    pub episodes: usize,
    /// Mean over all its episodes of each episode's RMS error (m).
    pub mean_rms_m: f64,
    /// Its energy per metre over the scripted gait's from the same starts, where the stage prices it
    /// ([`ValidationSet::price_energy`]); NaN where the scripted gait flew no energy.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub energy_ratio: Option<f64>,
    /// The left flap's fundamental (Hz), the mean over the episodes, where the stage reads it here
    /// ([`ValidationSet::read_flap_on`]); NaN where the wing did not flap.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flap_hz: Option<f64>,
}

impl ReferenceScore {
    fn of(name: &str, results: &[EpisodeResult]) -> Self {
        let rms: f64 = results.iter().map(EpisodeResult::rms_error_m).sum();
        Self {
            name: name.to_owned(),
            completed: results.iter().filter(|r| r.completed()).count(),
            episodes: results.len(),
            mean_rms_m: rms / results.len().max(1) as f64,
            energy_ratio: None,
            flap_hz: None,
        }
    }

    pub fn completed_percent(&self) -> f64 {
        100.0 * self.completed as f64 / self.episodes.max(1) as f64
    }

    /// Entry `name` flown `completed` of `episodes` at a mean RMS error of `mean_rms_m`, its energy not priced
    /// and its flap not read (tests).
    #[cfg(test)]
    pub(crate) fn flown(name: &str, completed: usize, episodes: usize, mean_rms_m: f64) -> Self {
        Self { name: name.to_owned(), completed, episodes, mean_rms_m, energy_ratio: None, flap_hz: None }
    }

    /// Whether this reference was drawn by the procedural generator (not named by the config).
    pub fn is_procedural(&self) -> bool {
        self.name.starts_with(PROCEDURAL_PREFIX)
    }

    /// Whether this entry was flown with randomized dynamics (`lateral~table3`).
    pub fn is_randomized(&self) -> bool {
        self.name.contains(RANDOMIZED_SEPARATOR)
    }
}

/// A checkpoint's score over the whole validation set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Score {
    /// Completed episodes over all entries (randomized ones too), in percent: the first key of the ranking.
    pub completed_percent: f64,
    /// Mean RMS error over all episodes (m): the second key, lower is better.
    pub mean_rms_m: f64,
    pub references: Vec<ReferenceScore>,
}

impl Score {
    fn of(references: Vec<ReferenceScore>) -> Self {
        let episodes: usize = references.iter().map(|r| r.episodes).sum();
        let completed: usize = references.iter().map(|r| r.completed).sum();
        let rms: f64 = references.iter().map(|r| r.mean_rms_m * r.episodes as f64).sum();
        Self {
            completed_percent: 100.0 * completed as f64 / episodes.max(1) as f64,
            mean_rms_m: rms / episodes.max(1) as f64,
            references,
        }
    }

    /// True when `self` ranks above `other`: more completed, or as many and a smaller RMS error.
    pub fn beats(&self, other: &Score) -> bool {
        self.completed_percent > other.completed_percent
            || (self.completed_percent == other.completed_percent && self.mean_rms_m < other.mean_rms_m)
    }

    /// Whether the gate's bars are met (the iteration bar is the caller's).
    pub fn meets(&self, gate: &Gate) -> bool {
        self.completes(gate) && self.rms_met(gate)
    }

    /// Whether the gate's completion bars are met (each entry's share of completed episodes, and the
    /// procedural ones' together), its RMS bars aside.
    pub fn completes(&self, gate: &Gate) -> bool {
        self.completes_entries(gate, true)
    }

    /// [`Self::completes`] without the randomized entries: every named (and procedural) entry's bar.
    pub fn completes_named(&self, gate: &Gate) -> bool {
        self.completes_entries(gate, false)
    }

    fn completes_entries(&self, gate: &Gate, randomized_too: bool) -> bool {
        let judged_alone = |r: &&ReferenceScore| {
            (gate.procedural_completed_percent.is_none() || !r.is_procedural())
                && (randomized_too || !r.is_randomized())
        };
        let bar = |r: &ReferenceScore| match gate.randomized_completed_percent {
            Some(randomized) if r.is_randomized() => randomized,
            _ => gate.completed_percent,
        };
        let each = self.references.iter().filter(judged_alone).all(|r| r.completed_percent() >= bar(r));
        let procedural = gate.procedural_completed_percent.is_none_or(|bar| {
            let drawn = || self.references.iter().filter(|r| r.is_procedural());
            let (completed, episodes) =
                (drawn().map(|r| r.completed).sum::<usize>(), drawn().map(|r| r.episodes).sum::<usize>());
            episodes == 0 || 100.0 * completed as f64 / episodes as f64 >= bar
        });
        each && procedural
    }

    /// Whether the gate's RMS bars are met: the mean over every entry (`max_rms_m`) and each entry's own.
    pub fn rms_met(&self, gate: &Gate) -> bool {
        gate.max_rms_m.is_none_or(|max| self.mean_rms_m <= max) && self.rms_bars_met(gate)
    }

    /// Whether every entry with its own RMS bar (`gate.reference_max_rms_m`) flew within it; an entry
    /// the validation set does not have cannot meet its bar.
    pub fn rms_bars_met(&self, gate: &Gate) -> bool {
        gate.reference_max_rms_m.iter().all(|(name, max)| self.reference(name).is_some_and(|r| r.mean_rms_m <= *max))
    }

    pub fn reference(&self, name: &str) -> Option<&ReferenceScore> {
        self.references.iter().find(|r| r.name == name)
    }

    /// The energy ratio of entry `name` over its validation's starts, where the gate priced it.
    pub fn energy_ratio(&self, name: &str) -> Option<f64> {
        self.reference(name).and_then(|r| r.energy_ratio)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn score(per_reference: &[(usize, usize, f64)]) -> Score {
        named_score(&vec!["r"; per_reference.len()], per_reference)
    }

    /// References named `NAME{k}` in order, for example `procedural-` for drawn ones.
    fn named_score(names: &[&str], per_reference: &[(usize, usize, f64)]) -> Score {
        Score::of(
            per_reference
                .iter()
                .enumerate()
                .map(|(k, &(completed, episodes, mean_rms_m))| {
                    ReferenceScore::flown(&format!("{}{k}", names[k]), completed, episodes, mean_rms_m)
                })
                .collect(),
        )
    }

    #[test]
    fn completion_ranks_first_then_the_rms_error() {
        let (a, b, c) = (score(&[(9, 10, 0.5)]), score(&[(10, 10, 0.9)]), score(&[(10, 10, 0.3)]));
        assert!(b.beats(&a) && !a.beats(&b), "more completed wins whatever the error");
        assert!(c.beats(&b) && !b.beats(&c), "as many completed: the smaller error wins");
        assert!(!c.beats(&c.clone()), "a tie is not a win (the earlier checkpoint stays)");
        let mixed = score(&[(10, 10, 0.2), (5, 10, 1.0)]);
        assert_eq!(mixed.completed_percent, 75.0);
        assert!((mixed.mean_rms_m - 0.6).abs() < 1e-12);
    }

    #[test]
    fn the_gate_asks_every_reference_and_the_mean_error() {
        let gate = Gate { max_rms_m: Some(0.5), ..Gate::completing(90.0) };
        assert!(score(&[(10, 10, 0.3), (9, 10, 0.4)]).meets(&gate));
        assert!(!score(&[(10, 10, 0.3), (8, 10, 0.4)]).meets(&gate), "one reference below the bar");
        assert!(!score(&[(10, 10, 0.6), (10, 10, 0.6)]).meets(&gate), "the error above its bar");
        assert!(score(&[(10, 10, 3.0)]).meets(&Gate { max_rms_m: None, ..gate.clone() }));
    }

    #[test]
    fn an_entry_with_its_own_rms_bar_is_judged_on_its_own_error() {
        let flown = Score::of(
            [("cruise", 0.1), ("longitudinal", 0.39), ("lateral~table3", 0.8)]
                .map(|(name, mean_rms_m)| ReferenceScore::flown(name, 10, 10, mean_rms_m))
                .to_vec(),
        );
        let bars = |bars: &[(&str, f64)]| Gate {
            max_rms_m: Some(0.45),
            reference_max_rms_m: bars.iter().map(|&(name, bar)| (name.to_owned(), bar)).collect(),
            ..Gate::completing(90.0)
        };
        assert!(flown.mean_rms_m <= 0.45 && flown.meets(&bars(&[])), "the mean over the entries is within its bar");
        assert!(!flown.meets(&bars(&[("longitudinal", 0.3)])), "0.39 m on longitudinal misses its 0.3 m bar");
        assert!(flown.meets(&bars(&[("longitudinal", 0.4), ("cruise", 0.3)])));
        assert!(flown.meets(&bars(&[("lateral~table3", 0.8)])), "a randomized entry's bar, met at equality");
        assert!(!flown.meets(&bars(&[("loop", 1.0)])), "an entry the set lacks cannot meet its bar");
    }

    #[test]
    fn procedural_references_can_be_judged_as_a_group() {
        let names = ["cruise", PROCEDURAL_PREFIX, PROCEDURAL_PREFIX];
        // The named reference flown, one drawn path flown, the other drawn path mostly not: 13/20 drawn.
        let flown = named_score(&names, &[(10, 10, 0.3), (10, 10, 0.3), (3, 10, 0.3)]);
        let each = Gate::completing(90.0);
        assert!(!flown.meets(&each), "without the group bar every drawn path is judged alone");
        let group = Gate { procedural_completed_percent: Some(65.0), ..each.clone() };
        assert!(flown.meets(&group), "13 of 20 drawn episodes meet a 65% group bar");
        assert!(!flown.meets(&Gate { procedural_completed_percent: Some(70.0), ..each.clone() }));
        let named_missed = named_score(&names, &[(8, 10, 0.3), (10, 10, 0.3), (10, 10, 0.3)]);
        assert!(!named_missed.meets(&group), "the group bar never excuses a named reference");
        assert!(flown.references[1].is_procedural() && !flown.references[0].is_procedural());
    }

    #[test]
    fn randomized_entries_have_their_own_bar_and_count_in_the_ranking() {
        let names = ["lateral", "lateral~table3", "longitudinal~table3"];
        let flown = named_score(&names, &[(10, 10, 0.2), (9, 10, 0.4), (8, 10, 0.5)]);
        assert!(flown.references[1].is_randomized() && !flown.references[0].is_randomized());
        let gate = Gate::completing(95.0);
        assert!(!flown.meets(&gate), "without their own bar randomized entries meet the nominal one");
        assert!(flown.meets(&Gate { randomized_completed_percent: Some(80.0), ..gate.clone() }));
        assert!(!flown.meets(&Gate { randomized_completed_percent: Some(85.0), ..gate.clone() }), "8/10 is below 85%");
        let nominal_missed = named_score(&names, &[(9, 10, 0.2), (10, 10, 0.4), (10, 10, 0.5)]);
        assert!(!nominal_missed.meets(&Gate { randomized_completed_percent: Some(0.0), ..gate.clone() }));
        let robust = named_score(&names, &[(10, 10, 0.2), (10, 10, 0.4), (10, 10, 0.5)]);
        assert!(robust.beats(&flown), "the randomized flights rank checkpoints too");
    }
}
