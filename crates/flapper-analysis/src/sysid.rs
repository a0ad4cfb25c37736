//! The identification experiment (paper IV-A, Fig. 4-5): the policy cruises along +x at 3.8 m/s and 10 m
//! while its target point is perturbed by small, smooth multisines, all three axes at once on
//! interleaved frequency grids (so each axis's input is uncorrelated with the others'). The input u is
//! the perturbation of the desired position (x along track, y lateral, z vertical), the output y the
//! robot's deviation from the unperturbed cruise, both with their record means removed. The body
//! bobs at the flapping frequency (about 4 Hz), far above the 0.05-0.8 Hz band; input and output pass
//! through the same zero-phase smoothing (two centred moving averages of 0.26 s), which removes the
//! bobbing and, applied to both, leaves the transfer function between them unchanged. Records from
//! some seeds identify the model, records from other seeds validate it.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_eval::tracking::{TrackingController, evaluate_tracking};
use flapper_plot::{BodeAxis, COLORS, Curve, Panel, PoleZeroMap};
use flapper_ppo::ActorCritic;
use flapper_sim::{RobotModel, Vec3};
use flapper_task::TaskConfig;
use flapper_task::reference::Reference;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::AnalysisError;
use crate::fit::{FitSettings, Record, Validation, fit_common_denominator, fit_order, validate};
use crate::linear_system::TransferFunction;

pub const AXES: [&str; 3] = ["x", "y", "z"];

/// The experiment's settings; the defaults are what `flapper sysid` runs.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SysidSettings {
    pub cruise_speed_mps: f64,
    pub altitude_m: f64,
    /// RMS of the perturbation of the target point on the axis being excited (m).
    pub amplitude_m: f64,
    /// The multisine repeats every `period_s`: its frequencies are the harmonics of 1 / period_s
    /// inside `band_hz`, all of them, with seeded random phases.
    pub period_s: f64,
    pub band_hz: [f64; 2],
    /// The perturbation fades in over this interval after the launch (s).
    pub fade_in_s: [f64; 2],
    /// Periods flown after the first, which is left to the launch and the transient: the output of
    /// these periods is averaged into one, which divides the part of the flight that does not follow
    /// the input (the closed loop's own slow wander) by about the square root of their number.
    pub averaged_periods: usize,
    /// Records per axis: each perturbs one axis only, so an axis's response is not mixed with the
    /// others' cross-coupling.
    pub identification_records: usize,
    pub validation_records: usize,
    /// Seeds of the phases: identification records use seed*1000 + 0.., validation seed*1000 + 500..
    pub seed: u64,
    /// lambda of the state-variable filter 1/(s + lambda)^3.
    pub filter_pole_radps: f64,
    /// The input at time t is the target perturbation at t + this lead (s, at most the policy's 0.6 s
    /// lookahead): the policy steers for points ahead of the current desired position. `None`:
    /// estimated from the identification records (the lead whose fitted model predicts them best).
    pub input_lead_s: Option<f64>,
}

impl Default for SysidSettings {
    fn default() -> Self {
        Self {
            cruise_speed_mps: flapper_sim::CRUISE_SPEED_MPS,
            altitude_m: 10.0,
            amplitude_m: 0.15,
            period_s: 20.0,
            band_hz: [0.05, 1.0],
            fade_in_s: [1.0, 3.0],
            averaged_periods: 16,
            identification_records: 2,
            validation_records: 1,
            seed: 1,
            filter_pole_radps: 2.0,
            input_lead_s: None,
        }
    }
}

impl SysidSettings {
    /// Seconds of one record: the settling period and the averaged ones.
    pub fn record_s(&self) -> f64 {
        self.period_s * (1 + self.averaged_periods) as f64
    }

    /// The multisine's harmonic numbers k: the frequencies k / period_s inside `band_hz`.
    pub fn harmonics(&self) -> Vec<usize> {
        let [lo, hi] = self.band_hz;
        (1..)
            .skip_while(|&k| k as f64 * (1.0 / self.period_s) < lo - 1e-9)
            .take_while(|&k| k as f64 * (1.0 / self.period_s) <= hi + 1e-9)
            .collect()
    }

    /// Seconds at the start of each record left out of the fit and the validation: the first period.
    pub fn skip_s(&self) -> f64 {
        self.period_s
    }
}

const CONTROL_PERIOD_S: f64 = 0.02;

/// Samples of each centred moving average that removes the flapping (0.26 s: its first null at 3.8 Hz).
pub const SMOOTHING_SAMPLES: usize = 13;

/// Two passes of a centred moving average of `SMOOTHING_SAMPLES` (the window shrinks at the ends).
pub fn smooth(signal: &[f64]) -> Vec<f64> {
    let pass = |x: &[f64]| -> Vec<f64> {
        let half = SMOOTHING_SAMPLES / 2;
        (0..x.len())
            .map(|k| {
                let (lo, hi) = (k.saturating_sub(half), (k + half + 1).min(x.len()));
                x[lo..hi].iter().sum::<f64>() / (hi - lo) as f64
            })
            .collect()
    };
    pass(&pass(signal))
}

/// A periodic multisine: `steps` samples every `dt_s` of the harmonics of 1 / `period_s` inside
/// `band_hz`, each with a random phase drawn from (`seed`, `axis`), RMS 1 once faded in over
/// `fade_in_s`.
pub fn multisine(seed: u64, axis: usize, steps: usize, dt_s: f64, s: &SysidSettings) -> Vec<f64> {
    let harmonics: Vec<f64> = s.harmonics().into_iter().map(|k| k as f64 * (1.0 / s.period_s)).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(axis as u64);
    let sines: Vec<(f64, f64)> = harmonics.iter().map(|&f| (f, rng.random_range(0.0..std::f64::consts::TAU))).collect();
    let amplitude = (2.0 / sines.len().max(1) as f64).sqrt();
    let [f0, f1] = s.fade_in_s;
    (0..steps)
        .map(|k| {
            let t = k as f64 * dt_s;
            let x = ((t - f0) / (f1 - f0)).clamp(0.0, 1.0);
            let fade = x * x * (3.0 - 2.0 * x);
            fade * amplitude * sines.iter().map(|(f, phase)| (std::f64::consts::TAU * f * t + phase).sin()).sum::<f64>()
        })
        .collect()
}

/// Which data set a record belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DataSet {
    Identification,
    Validation,
}

/// One flown record: one axis perturbed, smoothed, the output's periods after the first averaged.
#[derive(Debug, Clone)]
pub struct FlownRecord {
    pub set: DataSet,
    /// The axis perturbed (0 x, 1 y, 2 z).
    pub axis: usize,
    pub seed: u64,
    pub time_s: Vec<f64>,
    /// The perturbation of the target point on `axis`, one sample per control step from the first
    /// and as many beyond the last as the policy sees ahead.
    pub target: Vec<f64>,
    /// The robot's deviation from the nominal cruise on `axis`.
    pub output: Vec<f64>,
    /// Samples left out at the start (the first period).
    pub skip: usize,
}

impl FlownRecord {
    /// Input and output as fitted: the input leads the target by `lead` control steps; both with
    /// their means after `skip` removed.
    pub fn record(&self, lead: usize) -> Record {
        let n = self.output.len();
        let centred = |signal: &[f64]| {
            let tail = &signal[self.skip.min(n)..];
            let mean = tail.iter().sum::<f64>() / tail.len().max(1) as f64;
            signal.iter().map(|v| v - mean).collect::<Vec<f64>>()
        };
        Record { input: centred(&self.target[lead..lead + n]), output: centred(&self.output) }
    }

    /// The largest lead the record has samples for.
    pub fn max_lead(&self) -> usize {
        self.target.len() - self.output.len()
    }
}

/// Replaces each period after `skip` by the mean of those periods (`period` samples each).
fn average_periods(signal: &mut [f64], skip: usize, period: usize) {
    let count = (signal.len().saturating_sub(skip)) / period;
    if count < 2 {
        return;
    }
    let mean: Vec<f64> =
        (0..period).map(|k| (0..count).map(|p| signal[skip + p * period + k]).sum::<f64>() / count as f64).collect();
    for p in 0..count {
        signal[skip + p * period..skip + (p + 1) * period].copy_from_slice(&mean);
    }
}

/// Flies the identification and validation records with `policy` on its `task` from an exact start.
pub fn fly_records(
    robot: &RobotModel,
    policy: Arc<ActorCritic>,
    task: &TaskConfig,
    s: &SysidSettings,
) -> Result<Vec<FlownRecord>, AnalysisError> {
    let exact = crate::exact_start(task);
    let lookahead = exact.observation.lookahead_steps;
    let period_s = exact.control_period_s(robot.timestep_s());
    if (period_s - CONTROL_PERIOD_S).abs() > 1e-12 {
        return Err(AnalysisError::ControlRate { period_s });
    }
    let steps = (s.record_s() / CONTROL_PERIOD_S).round() as usize;
    let period = (s.period_s / CONTROL_PERIOD_S).round() as usize;
    let plan: Vec<(usize, DataSet, usize, u64)> = (0..3)
        .flat_map(|axis| {
            (0..s.identification_records).map(move |i| (DataSet::Identification, axis, s.seed * 1000 + i as u64)).chain(
                (0..s.validation_records).map(move |i| (DataSet::Validation, axis, s.seed * 1000 + 500 + i as u64)),
            )
        })
        .enumerate()
        .map(|(record, (set, axis, seed))| (record, set, axis, seed))
        .collect();
    let controller = TrackingController::Policy(policy);
    plan.par_iter()
        .map(|&(record, set, axis, seed)| {
            let total = steps + lookahead + 2;
            let target: Vec<f64> =
                multisine(seed, axis, total, CONTROL_PERIOD_S, s).into_iter().map(|v| v * s.amplitude_m).collect();
            let nominal = |k: usize| Vec3::new(s.cruise_speed_mps * k as f64 * CONTROL_PERIOD_S, 0.0, s.altitude_m);
            let points = (0..total)
                .map(|k| {
                    let mut point = nominal(k);
                    point[axis] += target[k];
                    point
                })
                .collect();
            let reference = Arc::new(Reference::new("sysid", CONTROL_PERIOD_S, points));
            let flown = evaluate_tracking(robot, &controller, &exact, reference, 1, seed)?.remove(0);
            let last_s = flown.steps.last().map_or(0.0, |st| st.time_s);
            if !flown.completed() {
                return Err(AnalysisError::RecordFailed {
                    record,
                    seed,
                    end: flown.end.name(),
                    time_s: last_s,
                    length_s: s.record_s(),
                    amplitude_m: s.amplitude_m,
                });
            }
            // Step k of the flight ends at control step k + 1: the target then is sample k + 1.
            let time_s: Vec<f64> = flown.steps.iter().map(|st| st.time_s).collect();
            let deviation: Vec<f64> =
                flown.steps.iter().enumerate().map(|(k, st)| (st.position_m - nominal(k + 1))[axis]).collect();
            let skip = period.min(deviation.len());
            let mut output = smooth(&deviation);
            average_periods(&mut output, skip, period);
            let target = smooth(&target[1..]);
            Ok(FlownRecord { set, axis, seed, time_s, target, output, skip })
        })
        .collect()
}

/// One axis's model as reported (the fields of `sysid.json`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct AxisModel {
    pub numerator: Vec<f64>,
    pub denominator: Vec<f64>,
    /// [re, im] pairs.
    pub poles: Vec<[f64; 2]>,
    pub zeros: Vec<[f64; 2]>,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub dc_gain: f64,
    /// The input is the target perturbation this far ahead (s).
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub input_lead_s: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mse_validation: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub fit_percent: f64,
    pub bibo_stable: bool,
    pub minimum_phase: bool,
}

impl AxisModel {
    fn of(model: &TransferFunction, lead: usize, validation: Validation) -> Self {
        let pairs = |roots: Vec<num_complex::Complex64>| roots.iter().map(|r| [r.re, r.im]).collect();
        Self {
            numerator: model.numerator.clone(),
            denominator: model.denominator.clone(),
            poles: pairs(model.poles()),
            zeros: pairs(model.zeros()),
            dc_gain: model.dc_gain(),
            input_lead_s: lead as f64 * CONTROL_PERIOD_S,
            mse_validation: validation.mse,
            fit_percent: validation.fit_percent,
            bibo_stable: model.bibo_stable(),
            minimum_phase: model.minimum_phase(),
        }
    }
}

/// Per axis x, y, z.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct AxisModels {
    pub x: AxisModel,
    pub y: AxisModel,
    pub z: AxisModel,
}

impl AxisModels {
    pub fn each(&self) -> [(&'static str, &AxisModel); 3] {
        [("x", &self.x), ("y", &self.y), ("z", &self.z)]
    }
}

/// A model with `poles` poles and `poles - 1` zeros, fitted at the axis's lead, on the validation records.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct OrderFit {
    pub poles: usize,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub fit_percent: f64,
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub mse_validation: f64,
    pub bibo_stable: bool,
    pub minimum_phase: bool,
}

/// Per axis, the validation of each model order tried, the order that validated best, and the
/// validation fit of the measured frequency response itself.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct OrderSelection {
    pub orders: Vec<OrderFit>,
    pub best_poles: usize,
    /// What a linear model of any order, fitted to these identification records, can be expected to
    /// reach: the validation fit (%) of the identification records' measured response at the
    /// harmonics ([`nonparametric_fit_percent`]). A parametric fit well below it is the model's
    /// fault; this itself well below 100% means the closed loop answers different multisines
    /// differently (it is not linear at this amplitude), which no model order fixes.
    #[serde(deserialize_with = "flapper_files::nan_as_null::number")]
    pub nonparametric_fit_percent: f64,
}

/// Orders tried by the order selection (poles; the headline model keeps the paper's 3).
pub const ORDERS: std::ops::RangeInclusive<usize> = 1..=6;

/// `sysid.json`: per axis the paper's eq. 9 form (three poles, two zeros) with its own denominator
/// and input lead at the top level, the paper's shared denominator beside it, and how the data
/// were made.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SysidReport {
    pub method: String,
    #[serde(flatten)]
    pub per_axis: AxisModels,
    pub common_denominator: AxisModels,
    /// x, y, z.
    pub order_selection: [OrderSelection; 3],
    pub experiment: SysidSettings,
}

/// The identified models and the records' inputs and outputs as fitted (each axis at its lead).
pub struct Identified {
    pub report: SysidReport,
    pub models: [TransferFunction; 3],
    /// Per axis, the leads (control steps) of its input.
    pub leads: [usize; 3],
}

/// Fits each axis at every candidate lead on its identification records and keeps the lead whose
/// model predicts them best (simulation error); then the shared-denominator form at those leads.
/// Both are validated on the validation records.
pub fn identify(records: &[FlownRecord], s: &SysidSettings) -> Result<Identified, AnalysisError> {
    let settings = FitSettings { dt_s: CONTROL_PERIOD_S, filter_pole_radps: s.filter_pole_radps, skip_s: s.skip_s() };
    let set = |which: DataSet, axis: usize, lead: usize| -> Vec<Record> {
        records.iter().filter(|r| r.set == which && r.axis == axis).map(|r| r.record(lead)).collect()
    };
    let max_lead = records.iter().map(FlownRecord::max_lead).min().unwrap_or(0);
    let candidates: Vec<usize> = match s.input_lead_s {
        Some(lead_s) => vec![((lead_s / CONTROL_PERIOD_S).round() as usize).min(max_lead)],
        None => (0..=max_lead).collect(),
    };
    let mut separate = Vec::new();
    let mut leads = [0; 3];
    for (axis, lead_of_axis) in leads.iter_mut().enumerate() {
        let best = candidates
            .par_iter()
            .filter_map(|&lead| {
                let identification = set(DataSet::Identification, axis, lead);
                let model = fit_common_denominator(std::slice::from_ref(&identification), &settings)?.remove(0);
                // A model whose response diverges predicts worst, but it is still a model.
                let error = validate(&model, &identification, &settings).mse;
                Some((if error.is_finite() { error } else { f64::INFINITY }, lead, model))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .ok_or(AnalysisError::FitFailed)?;
        *lead_of_axis = best.1;
        separate.push(best.2);
    }
    let identification: Vec<Vec<Record>> = (0..3).map(|a| set(DataSet::Identification, a, leads[a])).collect();
    let common = fit_common_denominator(&identification, &settings).ok_or(AnalysisError::FitFailed)?;
    let report_of = |models: &[TransferFunction]| {
        let m = |a: usize| {
            AxisModel::of(&models[a], leads[a], validate(&models[a], &set(DataSet::Validation, a, leads[a]), &settings))
        };
        AxisModels { x: m(0), y: m(1), z: m(2) }
    };
    let order_selection = [0, 1, 2].map(|a| {
        let identification = set(DataSet::Identification, a, leads[a]);
        let validation = set(DataSet::Validation, a, leads[a]);
        let orders: Vec<OrderFit> = ORDERS
            .filter_map(|poles| {
                let model = fit_order(std::slice::from_ref(&identification), &settings, poles)?.remove(0);
                let v = validate(&model, &validation, &settings);
                v.fit_percent.is_finite().then(|| OrderFit {
                    poles,
                    fit_percent: v.fit_percent,
                    mse_validation: v.mse,
                    bibo_stable: model.bibo_stable(),
                    minimum_phase: model.minimum_phase(),
                })
            })
            .collect();
        let best_poles = orders.iter().max_by(|a, b| a.fit_percent.total_cmp(&b.fit_percent)).map_or(3, |o| o.poles);
        OrderSelection {
            orders,
            best_poles,
            nonparametric_fit_percent: nonparametric_fit_percent(records, a, leads[a], s),
        }
    });
    let report = SysidReport {
        method:
            "state-variable-filter least squares (Young's SVF, lambda = filter_pole_radps), third order, numerator \
                 degree 2, per axis at the input lead whose model best predicts the identification records"
                .to_owned(),
        per_axis: report_of(&separate),
        common_denominator: report_of(&common),
        order_selection,
        experiment: s.clone(),
    };
    let models: [TransferFunction; 3] = separate.try_into().map_err(|_| AnalysisError::FitFailed)?;
    Ok(Identified { report, models, leads })
}

/// The discrete Fourier coefficient of `signal` (one period) at harmonic `k`.
fn harmonic_coefficient(signal: &[f64], k: usize) -> num_complex::Complex64 {
    let period = signal.len() as f64;
    signal
        .iter()
        .enumerate()
        .map(|(n, v)| v * num_complex::Complex64::from_polar(1.0, -std::f64::consts::TAU * (k * n) as f64 / period))
        .sum()
}

/// One averaged period of each of `records`' input and output (the first after the left-out one),
/// at `lead`; records too short for a period are left out.
fn one_period<'a>(records: impl Iterator<Item = &'a FlownRecord>, lead: usize, s: &SysidSettings) -> Vec<Record> {
    let period = (s.period_s / CONTROL_PERIOD_S).round() as usize;
    let skip = (s.skip_s() / CONTROL_PERIOD_S).round() as usize;
    records
        .map(|r| r.record(lead))
        .filter(|r| r.input.len() >= skip + period)
        .map(|r| Record {
            input: r.input[skip..skip + period].to_vec(),
            output: r.output[skip..skip + period].to_vec(),
        })
        .collect()
}

/// Output over input at each harmonic of `s`, averaged over `periods`.
fn mean_response(periods: &[Record], s: &SysidSettings) -> Vec<num_complex::Complex64> {
    s.harmonics()
        .into_iter()
        .map(|k| {
            let ratios = periods.iter().map(|p| harmonic_coefficient(&p.output, k) / harmonic_coefficient(&p.input, k));
            ratios.sum::<num_complex::Complex64>() / periods.len().max(1) as f64
        })
        .collect()
}

/// The measured frequency response of one axis at the multisine's harmonics: per record, the
/// discrete Fourier coefficients of one averaged period of output and input, their ratio averaged
/// over the axis's records. Entries are (frequency in Hz, gain as a complex number).
pub fn measured_response(
    records: &[FlownRecord],
    axis: usize,
    lead: usize,
    s: &SysidSettings,
) -> Vec<(f64, num_complex::Complex64)> {
    let periods = one_period(records.iter().filter(|r| r.axis == axis), lead, s);
    s.harmonics().into_iter().map(|k| k as f64 * (1.0 / s.period_s)).zip(mean_response(&periods, s)).collect()
}

/// The validation fit (%, as [`crate::fit::validate`]'s) of the measured response itself: the
/// identification records' mean output/input ratio at each harmonic, applied to each validation
/// record's input over one period, against its output over that period (mean over the validation
/// records). A linear time-invariant system gives nearly 100% (less what noise is left after the
/// averaging); a closed loop whose answer to a multisine depends on the multisine's phases (a
/// nonlinear one) gives less, and no linear model fitted to the same records does much better.
pub fn nonparametric_fit_percent(records: &[FlownRecord], axis: usize, lead: usize, s: &SysidSettings) -> f64 {
    let of = |set: DataSet| one_period(records.iter().filter(|r| r.axis == axis && r.set == set), lead, s);
    let (identification, validation) = (of(DataSet::Identification), of(DataSet::Validation));
    if identification.is_empty() || validation.is_empty() {
        return f64::NAN;
    }
    let response = mean_response(&identification, s);
    let fits: Vec<f64> = validation
        .iter()
        .map(|v| {
            let period = v.output.len();
            let input: Vec<num_complex::Complex64> =
                s.harmonics().into_iter().map(|k| harmonic_coefficient(&v.input, k)).collect();
            // The predicted period: the real signal whose coefficient at harmonic k is H_k U_k.
            let predicted = (0..period).map(|n| {
                s.harmonics()
                    .into_iter()
                    .zip(input.iter().zip(&response))
                    .map(|(k, (u, h))| {
                        let turn = std::f64::consts::TAU * (k * n) as f64 / period as f64;
                        2.0 / period as f64 * (h * u * num_complex::Complex64::from_polar(1.0, turn)).re
                    })
                    .sum::<f64>()
            });
            let mean = v.output.iter().sum::<f64>() / period as f64;
            let error: f64 = v.output.iter().zip(predicted).map(|(y, p)| (y - mean - p).powi(2)).sum();
            let spread: f64 = v.output.iter().map(|y| (y - mean).powi(2)).sum();
            100.0 * (1.0 - (error / spread).sqrt())
        })
        .collect();
    fits.iter().sum::<f64>() / fits.len() as f64
}

/// Magnitude (dB) and phase (degrees) of `gains`, the phase unwrapped along the frequencies, or, with
/// `anchor`, placed within 180 degrees of the anchor's phase at the same frequency.
fn bode_points(gains: &[(f64, num_complex::Complex64)], anchor: Option<&dyn Fn(f64) -> f64>) -> Vec<(f64, f64, f64)> {
    let mut previous: Option<f64> = None;
    gains
        .iter()
        .map(|&(f, g)| {
            let mut phase = g.arg().to_degrees();
            if let Some(target) = anchor.map(|a| a(f)).or(previous) {
                phase += 360.0 * ((target - phase) / 360.0).round();
            }
            previous = Some(phase);
            (f, 20.0 * g.norm().log10(), phase)
        })
        .collect()
}

/// The model's Bode curve over the band (and beyond by a factor 2) and the measured response.
fn bode_axis(
    title: String,
    model: &TransferFunction,
    measured: &[(f64, num_complex::Complex64)],
    s: &SysidSettings,
) -> BodeAxis {
    let (lo, hi) = (0.5 * s.band_hz[0], 2.0 * s.band_hz[1]);
    let dense: Vec<(f64, num_complex::Complex64)> = (0..300)
        .map(|i| lo * (hi / lo).powf(i as f64 / 299.0))
        .map(|f| (f, model.frequency_response(std::f64::consts::TAU * f)))
        .collect();
    let model_points = bode_points(&dense, None);
    let model_phase =
        |f: f64| model_points.iter().min_by(|a, b| (a.0 - f).abs().total_cmp(&(b.0 - f).abs())).map_or(0.0, |p| p.2);
    BodeAxis { title, measured: bode_points(measured, Some(&model_phase)), model: model_points }
}

/// One row of `sysid_io.csv`.
#[derive(Debug, Serialize)]
struct IoRow {
    time_s: f64,
    u_x: f64,
    u_y: f64,
    u_z: f64,
    y_x: f64,
    y_y: f64,
    y_z: f64,
    set: DataSet,
    /// The record's number within its set: rows of one record are one simulation from rest.
    record: usize,
}

/// The records side by side as `sysid_io.csv` holds them: the k-th record of a set gives each axis
/// its k-th record (in which that axis was perturbed), at that axis's lead.
fn paired_records(records: &[FlownRecord], leads: [usize; 3]) -> Vec<(DataSet, usize, [Record; 3], &[f64])> {
    let mut paired = Vec::new();
    for set in [DataSet::Identification, DataSet::Validation] {
        let of_axis =
            |axis: usize| -> Vec<&FlownRecord> { records.iter().filter(|r| r.set == set && r.axis == axis).collect() };
        let [x, y, z] = [of_axis(0), of_axis(1), of_axis(2)];
        for k in 0..x.len().min(y.len()).min(z.len()) {
            let axes = [x[k].record(leads[0]), y[k].record(leads[1]), z[k].record(leads[2])];
            paired.push((set, k, axes, x[k].time_s.as_slice()));
        }
    }
    paired
}

/// Writes `sysid.json`, `sysid_io.csv`, `pole_zero.svg`, `validation.svg` and `bode.svg` into `dir`.
pub fn write_sysid_files(
    dir: &Path,
    identified: &Identified,
    records: &[FlownRecord],
) -> Result<Vec<PathBuf>, AnalysisError> {
    let Identified { report, models, leads } = identified;
    let fail =
        |path: &Path, e: &dyn std::fmt::Display| AnalysisError::Write { path: path.to_owned(), message: e.to_string() };
    let json = dir.join("sysid.json");
    flapper_files::write_json(&json, report).map_err(|e| fail(&json, &e))?;

    let io = dir.join("sysid_io.csv");
    let paired = paired_records(records, *leads);
    let rows = paired.iter().flat_map(|(set, record, axes, time_s)| {
        let [x, y, z] = axes;
        (0..time_s.len()).map(move |k| IoRow {
            time_s: time_s[k],
            u_x: x.input[k],
            u_y: y.input[k],
            u_z: z.input[k],
            y_x: x.output[k],
            y_y: y.output[k],
            y_z: z.output[k],
            set: *set,
            record: *record,
        })
    });
    flapper_files::write_csv_records(&io, rows).map_err(|e| fail(&io, &e))?;

    let pole_zero = dir.join("pole_zero.svg");
    let maps: Vec<PoleZeroMap> = report
        .per_axis
        .each()
        .iter()
        .map(|(axis, m)| PoleZeroMap {
            title: format!("q_{axis}: poles and zeros"),
            poles: m.poles.iter().map(|p| (p[0], p[1])).collect(),
            zeros: m.zeros.iter().map(|z| (z[0], z[1])).collect(),
        })
        .collect();
    flapper_plot::draw_pole_zero_maps(&pole_zero, &maps).map_err(|e| fail(&pole_zero, &e))?;

    let validation = dir.join("validation.svg");
    let skip = (report.experiment.skip_s() / CONTROL_PERIOD_S).ceil() as usize;
    let panels: Vec<Panel> = (0..3)
        .filter_map(|a| {
            let (_, _, axes, time_s) = paired.iter().find(|p| p.0 == DataSet::Validation)?;
            let record = &axes[a];
            let predicted = models[a].simulate(&record.input, CONTROL_PERIOD_S);
            // Three periods after the left-out first one: the rest repeats them (the periods are averaged).
            let shown = 3 * skip;
            let series =
                |values: &[f64]| time_s.iter().zip(values).skip(skip).take(shown).map(|(&t, &v)| (t, v)).collect();
            let m = report.per_axis.each()[a].1;
            Some(Panel {
                title: format!(
                    "{}: validation record, fit {:.1}%, MSE {:.2e} m^2, input lead {:.2} s",
                    AXES[a], m.fit_percent, m.mse_validation, m.input_lead_s
                ),
                x_label: "time (s)",
                y_label: "deviation (m)",
                curves: vec![
                    Curve {
                        label: "target perturbation ahead (input)".into(),
                        points: series(&record.input),
                        color: COLORS[2],
                        dashed: true,
                    },
                    Curve {
                        label: "flown (measured, periods averaged)".into(),
                        points: series(&record.output),
                        color: COLORS[0],
                        dashed: false,
                    },
                    Curve {
                        label: "model (predicted)".into(),
                        points: series(&predicted),
                        color: COLORS[1],
                        dashed: false,
                    },
                ],
                equal_aspect: false,
            })
        })
        .collect();
    flapper_plot::draw(&validation, (1100, 1000), &panels, (3, 1)).map_err(|e| fail(&validation, &e))?;

    let bode = dir.join("bode.svg");
    let axes: Vec<BodeAxis> = (0..3)
        .map(|a| {
            let measured = measured_response(records, a, leads[a], &report.experiment);
            let title = format!("{}, input {:.2} s ahead", AXES[a], leads[a] as f64 * CONTROL_PERIOD_S);
            bode_axis(title, &models[a], &measured, &report.experiment)
        })
        .collect();
    flapper_plot::draw_bode(&bode, &axes).map_err(|e| fail(&bode, &e))?;
    Ok(vec![json, io, pole_zero, validation, bode])
}
