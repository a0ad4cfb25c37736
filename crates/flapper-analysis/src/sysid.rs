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

use flapper_eval::tracking::{Pilot, evaluate_tracking};
use flapper_plot::{COLORS, Curve, Panel, PoleZeroMap};
use flapper_ppo::ActorCritic;
use flapper_sim::{RobotModel, Vec3};
use flapper_task::TaskConfig;
use flapper_task::reference::Reference;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Serialize;

use crate::AnalysisError;
use crate::fit::{FitSettings, Record, Validation, fit_common_denominator, validate};
use crate::linear_system::TransferFunction;

pub const AXES: [&str; 3] = ["x", "y", "z"];

/// The experiment's settings; the defaults are what `flapper sysid` runs.
#[derive(Debug, Clone, Serialize)]
pub struct SysidSettings {
    pub cruise_speed_mps: f64,
    pub altitude_m: f64,
    /// RMS of each axis's perturbation of the target point.
    pub amplitude_m: f64,
    /// Band of the multisines (Hz); each axis has `sines_per_axis` frequencies in it.
    pub band_hz: [f64; 2],
    pub sines_per_axis: usize,
    /// The perturbation fades in over this interval after the launch (s).
    pub fade_in_s: [f64; 2],
    pub record_s: f64,
    pub identification_records: usize,
    pub validation_records: usize,
    /// Seeds of the phases: identification records use seed*1000 + 0.., validation seed*1000 + 500..
    pub seed: u64,
    /// Seconds at the start of each record left out of the fit and the validation (launch, fade-in).
    pub skip_s: f64,
    /// lambda of the state-variable filter 1/(s + lambda)^3.
    pub filter_pole_radps: f64,
    /// The input at time t is the target perturbation at t + this (s, at most the policy's 0.6 s
    /// lookahead). 0 is the paper's input, the current desired position.
    pub input_lead_s: f64,
}

impl Default for SysidSettings {
    fn default() -> Self {
        Self {
            cruise_speed_mps: flapper_sim::CRUISE_SPEED_MPS,
            altitude_m: 10.0,
            amplitude_m: 0.15,
            band_hz: [0.05, 0.8],
            sines_per_axis: 8,
            fade_in_s: [1.0, 3.0],
            record_s: 30.0,
            identification_records: 4,
            validation_records: 2,
            seed: 1,
            skip_s: 5.0,
            filter_pole_radps: 2.0,
            input_lead_s: 0.0,
        }
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

/// The perturbation of one axis (0 x, 1 y, 2 z): `steps` samples every `dt_s` of a sum of sines with
/// seeded random phases on that axis's frequency grid, RMS 1 once faded in over 1-3 s. Grids
/// interleave: axis a uses frequencies f_lo (f_hi/f_lo)^((3k + a) / (3K - 1)), k < K = 8, over
/// 0.05-0.8 Hz.
pub fn multisine(seed: u64, axis: usize, steps: usize, dt_s: f64) -> Vec<f64> {
    let s = SysidSettings::default();
    unit_multisine(seed, axis, steps, dt_s, &s)
}

fn unit_multisine(seed: u64, axis: usize, steps: usize, dt_s: f64, s: &SysidSettings) -> Vec<f64> {
    let k_count = s.sines_per_axis;
    let [lo, hi] = s.band_hz;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(axis as u64);
    let sines: Vec<(f64, f64)> = (0..k_count)
        .map(|k| {
            let exponent = (3 * k + axis) as f64 / (3 * k_count - 1) as f64;
            (lo * (hi / lo).powf(exponent), rng.random_range(0.0..std::f64::consts::TAU))
        })
        .collect();
    let amplitude = (2.0 / k_count as f64).sqrt();
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

/// One flown record: per axis the input (target perturbation) and output (deviation), means removed.
#[derive(Debug, Clone)]
pub struct FlownRecord {
    pub set: DataSet,
    pub seed: u64,
    pub time_s: Vec<f64>,
    pub axes: [Record; 3],
}

/// Flies the identification and validation records with `policy` on its `task` from an exact start.
pub fn fly_records(
    robot: &RobotModel,
    policy: Arc<ActorCritic>,
    task: &TaskConfig,
    s: &SysidSettings,
) -> Result<Vec<FlownRecord>, AnalysisError> {
    let mut exact = task.clone();
    exact.initial_state.position_offset_m = [0.0; 3];
    exact.initial_state.speed_offset_mps = 0.0;
    exact.initial_state.attitude_offset_deg = 0.0;
    let lookahead = exact.observation.lookahead_steps;
    let period_s = exact.control_period_s(robot.timestep_s());
    if (period_s - CONTROL_PERIOD_S).abs() > 1e-12 {
        return Err(AnalysisError::ControlRate { period_s });
    }
    let steps = (s.record_s / CONTROL_PERIOD_S).round() as usize;
    let plan: Vec<(usize, DataSet, u64)> = (0..s.identification_records)
        .map(|i| (DataSet::Identification, s.seed * 1000 + i as u64))
        .chain((0..s.validation_records).map(|i| (DataSet::Validation, s.seed * 1000 + 500 + i as u64)))
        .enumerate()
        .map(|(record, (set, seed))| (record, set, seed))
        .collect();
    let pilot = Pilot::Policy(policy);
    plan.par_iter()
        .map(|&(record, set, seed)| {
            let total = steps + lookahead + 2;
            let perturbation: Vec<Vec<f64>> = (0..3)
                .map(|a| {
                    unit_multisine(seed, a, total, CONTROL_PERIOD_S, s).into_iter().map(|v| v * s.amplitude_m).collect()
                })
                .collect();
            let nominal = |k: usize| Vec3::new(s.cruise_speed_mps * k as f64 * CONTROL_PERIOD_S, 0.0, s.altitude_m);
            let points = (0..total)
                .map(|k| nominal(k) + Vec3::new(perturbation[0][k], perturbation[1][k], perturbation[2][k]))
                .collect();
            let reference = Arc::new(Reference::new("sysid", CONTROL_PERIOD_S, points));
            let flown = evaluate_tracking(robot, &pilot, &exact, reference, 1, seed)?.remove(0);
            let last_s = flown.steps.last().map_or(0.0, |st| st.time_s);
            if !flown.completed() {
                return Err(AnalysisError::RecordFailed {
                    record,
                    seed,
                    end: flown.end.name(),
                    time_s: last_s,
                    length_s: s.record_s,
                    amplitude_m: s.amplitude_m,
                });
            }
            let skip = (s.skip_s / CONTROL_PERIOD_S).ceil() as usize;
            let lead = ((s.input_lead_s / CONTROL_PERIOD_S).round() as usize).min(lookahead);
            let mut time_s = Vec::new();
            let mut io: [(Vec<f64>, Vec<f64>); 3] = Default::default();
            for (k, st) in flown.steps.iter().enumerate() {
                let step = k + 1;
                time_s.push(st.time_s);
                let deviation = st.position_m - nominal(step);
                for a in 0..3 {
                    io[a].0.push(perturbation[a][step + lead]);
                    io[a].1.push(deviation[a]);
                }
            }
            let axes = io.map(|(input, output)| {
                let [input, output] = [input, output].map(|signal| {
                    let mut smoothed = smooth(&signal);
                    let tail = &smoothed[skip.min(smoothed.len())..];
                    let mean = tail.iter().sum::<f64>() / tail.len().max(1) as f64;
                    smoothed.iter_mut().for_each(|v| *v -= mean);
                    smoothed
                });
                Record { input, output }
            });
            Ok(FlownRecord { set, seed, time_s, axes })
        })
        .collect()
}

/// One axis's model as reported (the fields of `sysid.json`).
#[derive(Debug, Clone, Serialize)]
pub struct AxisModel {
    pub numerator: Vec<f64>,
    pub denominator: Vec<f64>,
    /// [re, im] pairs.
    pub poles: Vec<[f64; 2]>,
    pub zeros: Vec<[f64; 2]>,
    pub dc_gain: f64,
    pub mse_validation: f64,
    pub fit_percent: f64,
    pub bibo_stable: bool,
    pub minimum_phase: bool,
}

impl AxisModel {
    fn of(model: &TransferFunction, validation: Validation) -> Self {
        let pairs = |roots: Vec<num_complex::Complex64>| roots.iter().map(|r| [r.re, r.im]).collect();
        Self {
            numerator: model.numerator.clone(),
            denominator: model.denominator.clone(),
            poles: pairs(model.poles()),
            zeros: pairs(model.zeros()),
            dc_gain: model.dc_gain(),
            mse_validation: validation.mse,
            fit_percent: validation.fit_percent,
            bibo_stable: model.bibo_stable(),
            minimum_phase: model.minimum_phase(),
        }
    }
}

/// Per axis x, y, z.
#[derive(Debug, Clone, Serialize)]
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

/// `sysid.json`: the paper's form (one denominator for the three axes) at the top level, per-axis
/// denominators beside it, and how the data were made.
#[derive(Debug, Clone, Serialize)]
pub struct SysidReport {
    pub method: &'static str,
    #[serde(flatten)]
    pub common: AxisModels,
    pub per_axis_denominators: AxisModels,
    pub experiment: SysidSettings,
}

/// Fits both model forms to the identification records and validates them on the others.
pub fn identify(
    records: &[FlownRecord],
    s: &SysidSettings,
) -> Result<(SysidReport, [TransferFunction; 3]), AnalysisError> {
    let settings = FitSettings { dt_s: CONTROL_PERIOD_S, filter_pole_radps: s.filter_pole_radps, skip_s: s.skip_s };
    let set = |which: DataSet, axis: usize| -> Vec<Record> {
        records.iter().filter(|r| r.set == which).map(|r| r.axes[axis].clone()).collect()
    };
    let identification: Vec<Vec<Record>> = (0..3).map(|a| set(DataSet::Identification, a)).collect();
    let common = fit_common_denominator(&identification, &settings).ok_or(AnalysisError::FitFailed)?;
    let mut separate = Vec::new();
    for axis in &identification {
        separate.push(
            fit_common_denominator(std::slice::from_ref(axis), &settings).ok_or(AnalysisError::FitFailed)?.remove(0),
        );
    }
    let report_of = |models: &[TransferFunction]| {
        let m = |a: usize| AxisModel::of(&models[a], validate(&models[a], &set(DataSet::Validation, a), &settings));
        AxisModels { x: m(0), y: m(1), z: m(2) }
    };
    let report = SysidReport {
        method: "state-variable-filter least squares, third order, numerator degree 2 (Young's SVF, lambda = filter_pole_radps)",
        common: report_of(&common),
        per_axis_denominators: report_of(&separate),
        experiment: s.clone(),
    };
    let common: [TransferFunction; 3] = common.try_into().map_err(|_| AnalysisError::FitFailed)?;
    Ok((report, common))
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
}

/// Writes `sysid.json`, `sysid_io.csv`, `pole_zero.svg` and `validation.svg` into `dir`.
pub fn write_sysid_files(
    dir: &Path,
    report: &SysidReport,
    models: &[TransferFunction; 3],
    records: &[FlownRecord],
) -> Result<Vec<PathBuf>, AnalysisError> {
    let fail =
        |path: &Path, e: &dyn std::fmt::Display| AnalysisError::Write { path: path.to_owned(), message: e.to_string() };
    let json = dir.join("sysid.json");
    flapper_files::write_json(&json, report).map_err(|e| fail(&json, &e))?;

    let io = dir.join("sysid_io.csv");
    let rows = records.iter().flat_map(|r| {
        let [x, y, z] = &r.axes;
        (0..r.time_s.len()).map(move |k| IoRow {
            time_s: r.time_s[k],
            u_x: x.input[k],
            u_y: y.input[k],
            u_z: z.input[k],
            y_x: x.output[k],
            y_y: y.output[k],
            y_z: z.output[k],
            set: r.set,
        })
    });
    flapper_files::write_csv_records(&io, rows).map_err(|e| fail(&io, &e))?;

    let pole_zero = dir.join("pole_zero.svg");
    let maps: Vec<PoleZeroMap> = report
        .common
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
    if let Some(first) = records.iter().find(|r| r.set == DataSet::Validation) {
        let skip = (report.experiment.skip_s / CONTROL_PERIOD_S).ceil() as usize;
        let panels: Vec<Panel> = (0..3)
            .map(|a| {
                let predicted = models[a].simulate(&first.axes[a].input, CONTROL_PERIOD_S);
                let series =
                    |values: &[f64]| first.time_s.iter().zip(values).skip(skip).map(|(&t, &v)| (t, v)).collect();
                let m = report.common.each()[a].1;
                Panel {
                    title: format!(
                        "{}: validation record (seed {}), fit {:.1}%, MSE {:.2e} m^2",
                        AXES[a], first.seed, m.fit_percent, m.mse_validation
                    ),
                    x_label: "time (s)",
                    y_label: "deviation (m)",
                    curves: vec![
                        Curve {
                            label: "target perturbation (input)".into(),
                            points: series(&first.axes[a].input),
                            color: COLORS[2],
                            dashed: true,
                        },
                        Curve {
                            label: "flown (measured)".into(),
                            points: series(&first.axes[a].output),
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
                }
            })
            .collect();
        flapper_plot::draw(&validation, (1100, 1000), &panels, (3, 1)).map_err(|e| fail(&validation, &e))?;
    }
    Ok(vec![json, io, pole_zero, validation])
}
