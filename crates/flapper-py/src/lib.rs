//! flapper from Python: the Rust side of the `flapper` package. The Gymnasium class lives in
//! `python/flapper/vector_env.py`; this module gives it the vectorized flight environments
//! ([`flapper_task::FlightVecEnv`], stepped on Rust threads with the GIL released), the shipped
//! policies and the named references. Every flapper error becomes a Python `ValueError` carrying
//! flapper's own message.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use flapper_deploy::{DeployablePolicy, PolicyArrays};
use flapper_eval::FlightPolicyFile;

use flapper_ppo::ActorCritic;
use flapper_ppo::actor_critic::InferenceScratch;
use flapper_sim::RobotModel;
use flapper_task::action::ACTION_SIZE;
use flapper_task::reference::csv_file::reference_from_points;
use flapper_task::reference::named::NAMED_REFERENCES;
use flapper_task::reference::{NAMED_START_M, Reference, resolve};
use flapper_task::termination::EpisodeEnd;
use flapper_task::{FlightVecEnv, ReferenceSource, TaskConfig};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

fn value_error(error: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(error.to_string())
}

/// How an episode ended, as the info dict names it ("" while it goes on).
fn end_name(end: EpisodeEnd) -> &'static str {
    match end {
        EpisodeEnd::TooFarFromTarget => "too_far",
        EpisodeEnd::AttitudeLimit => "attitude",
        EpisodeEnd::TimeLimit => "time_limit",
        EpisodeEnd::ReferenceEnd => "reference_end",
        EpisodeEnd::SimulationFault => "sim_fault",
    }
}

/// The task of a stage preset, a run config (TOML, as `flapper train --config`) or a policy file
/// (the task it was trained on). Exactly one may be given; none means stage 1.
fn task_of(stage: Option<i64>, config: Option<&str>, policy: Option<&str>) -> PyResult<TaskConfig> {
    match (stage, config, policy) {
        (Some(stage), None, None) => TaskConfig::stage(stage).map_err(value_error),
        (None, Some(path), None) => {
            Ok(flapper_train::config::TrainConfig::load(Path::new(path), None).map_err(value_error)?.task)
        }
        (None, None, Some(path)) => Ok(flapper_eval::load_flight_policy(Path::new(path)).map_err(value_error)?.1),
        (None, None, None) => TaskConfig::stage(1).map_err(value_error),
        _ => Err(PyValueError::new_err("give one of stage, config or policy, not several")),
    }
}

/// A reference from Python: a name, a CSV path, or an array of positions (rows x, y, z in metres)
/// sampled at the control rate.
fn reference_of(reference: &Bound<'_, PyAny>, dt_s: f64, lookahead_steps: usize) -> PyResult<Reference> {
    if let Ok(name) = reference.extract::<String>() {
        return resolve(&name, dt_s, lookahead_steps).map_err(value_error);
    }
    let points: PyReadonlyArray2<f64> = reference.extract().map_err(|_| {
        PyTypeError::new_err(
            "a reference is a name, a CSV path, or a float64 array of shape (rows, 3): x, y, z in metres",
        )
    })?;
    if points.shape()[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "a reference array has 3 columns (x, y, z), got shape {:?}",
            points.shape()
        )));
    }
    let rows: Vec<[f64; 3]> = points.as_array().rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect();
    reference_from_points(&rows, "array", dt_s, lookahead_steps).map_err(value_error)
}

/// N flight environments with automatic reset (same step: an ended episode's observation row is
/// already the next episode's first). The Gymnasium class `flapper.FlightVectorEnv` wraps it.
#[pyclass(module = "flapper._flapper", unsendable)]
struct VecEnvCore {
    envs: FlightVecEnv,
    task: TaskConfig,
    dt_s: f64,
}

#[pymethods]
impl VecEnvCore {
    #[new]
    #[pyo3(signature = (num_envs, stage=None, config=None, policy=None, reference=None, evaluation=false, seed=0, threads=0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        num_envs: usize,
        stage: Option<i64>,
        config: Option<&str>,
        policy: Option<&str>,
        reference: Option<&Bound<'_, PyAny>>,
        evaluation: bool,
        seed: u64,
        threads: usize,
    ) -> PyResult<Self> {
        if !(1..=65_536).contains(&num_envs) {
            return Err(PyValueError::new_err(format!("num_envs must be 1 to 65536, got {num_envs}")));
        }
        if threads > 1024 {
            return Err(PyValueError::new_err(format!("threads must be 0 (one per core) to 1024, got {threads}")));
        }
        let robot = RobotModel::flapper().map_err(value_error)?;
        let mut task = task_of(stage, config, policy)?;
        let dt_s = task.control_period_s(robot.timestep_s());
        let lookahead = task.observation.lookahead_steps;
        let source = match reference {
            None if evaluation => {
                return Err(PyValueError::new_err("evaluation=True flies a fixed reference: give reference"));
            }
            None => ReferenceSource::Procedural,
            Some(reference) => {
                let reference = Arc::new(reference_of(reference, dt_s, lookahead)?);
                if evaluation {
                    task = flapper_eval::tracking::evaluation_task(&task, &reference);
                }
                ReferenceSource::Fixed(reference)
            }
        };
        let task_for_envs = task.clone();
        let envs = py
            .detach(move || FlightVecEnv::new(&robot, task_for_envs, source, num_envs, seed, threads))
            .map_err(value_error)?;
        Ok(Self { envs, task, dt_s })
    }

    #[getter]
    fn num_envs(&self) -> usize {
        self.envs.len()
    }

    #[getter]
    fn observation_size(&self) -> usize {
        self.envs.observation_size()
    }

    #[getter]
    fn action_size(&self) -> usize {
        ACTION_SIZE
    }

    /// Seconds of simulated time per step (the 50 Hz policy rate).
    #[getter]
    fn dt_s(&self) -> f64 {
        self.dt_s
    }

    #[getter]
    fn max_episode_steps(&self) -> usize {
        self.task.episode.max_steps
    }

    /// The task's settings as TOML (the `[task]` table of a run config).
    #[getter]
    fn task_toml(&self) -> PyResult<String> {
        toml::to_string(&self.task).map_err(value_error)
    }

    /// Starts a new episode in every environment: with `seed`, each environment's random stream is
    /// drawn afresh from (seed, its index), exactly as a new batch built with that seed; without,
    /// each continues its stream. References set per environment stay. Returns the observations.
    #[pyo3(signature = (seed=None))]
    fn reset<'py>(&mut self, py: Python<'py>, seed: Option<u64>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let envs = &mut self.envs;
        py.detach(|| match seed {
            Some(seed) => envs.restart(seed),
            None => envs.reset_all(),
        })
        .map_err(value_error)?;
        self.observations(py)
    }

    fn observations<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f32>>> {
        rows(py, self.envs.observations(), self.envs.observation_size())
    }

    /// Steps every environment with its row of `actions` (float32, [N, 5], finite). Returns
    /// (observations, rewards, terminated, truncated, info arrays); see `vector_env.py`.
    #[allow(clippy::type_complexity)]
    fn step<'py>(&mut self, py: Python<'py>, actions: PyReadonlyArray2<'py, f32>) -> PyResult<Bound<'py, PyDict>> {
        let (n, shape) = (self.envs.len(), actions.shape().to_vec());
        if shape != [n, ACTION_SIZE] {
            return Err(PyValueError::new_err(format!("actions must have shape ({n}, {ACTION_SIZE}), got {shape:?}")));
        }
        let flat: Vec<f32> = actions.as_array().iter().copied().collect();
        if let Some(k) = flat.iter().position(|a| !a.is_finite()) {
            return Err(PyValueError::new_err(format!(
                "action {} of environment {} is {}: actions must be finite",
                k % ACTION_SIZE,
                k / ACTION_SIZE,
                flat[k]
            )));
        }
        let envs = &mut self.envs;
        py.detach(|| envs.step(&flat)).map_err(value_error)?;
        let size = self.envs.observation_size();
        let mut end_reason = vec![""; n];
        let mut episode_return = vec![0.0f64; n];
        let mut episode_length = vec![0usize; n];
        for info in self.envs.take_finished_episodes() {
            end_reason[info.env_index] = end_name(info.end);
            episode_return[info.env_index] = info.episode_return;
            episode_length[info.env_index] = info.length;
        }
        let terms = self.envs.reward_terms();
        let term = |f: fn(&flapper_task::reward::RewardTerms) -> f64| {
            terms.iter().map(f).collect::<Vec<f64>>().into_pyarray(py)
        };
        let out = PyDict::new(py);
        out.set_item("observations", rows(py, self.envs.observations(), size)?)?;
        out.set_item("final_observations", rows(py, self.envs.final_observations(), size)?)?;
        out.set_item("rewards", PyArray1::from_slice(py, self.envs.rewards()))?;
        out.set_item("terminated", PyArray1::from_slice(py, self.envs.terminated()))?;
        out.set_item("truncated", PyArray1::from_slice(py, self.envs.truncated()))?;
        out.set_item("position_error_m", PyArray1::from_slice(py, self.envs.position_errors_m()))?;
        out.set_item("end_reason", end_reason)?;
        out.set_item("episode_return", episode_return.into_pyarray(py))?;
        out.set_item("episode_length", episode_length.into_pyarray(py))?;
        out.set_item("reward_position", term(|t| t.position))?;
        out.set_item("reward_body_rate", term(|t| t.body_rate))?;
        out.set_item("reward_level", term(|t| t.level))?;
        out.set_item("reward_energy", term(|t| t.energy))?;
        out.set_item("reward_action_rate", term(|t| t.action_rate))?;
        out.set_item("reward_flap_rate", term(|t| t.flap_rate))?;
        out.set_item("reward_glide_hold", term(|t| t.glide_hold))?;
        Ok(out)
    }

    /// Environment `index` (every one when None) flies `reference` (a name, CSV path or [rows, 3]
    /// float64 array, resolved once) from now on, starting a new episode on it at once. Returns the
    /// observations [N, obs].
    #[pyo3(signature = (reference, index=None))]
    fn set_reference<'py>(
        &mut self,
        py: Python<'py>,
        reference: &Bound<'py, PyAny>,
        index: Option<usize>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        if let Some(index) = index.filter(|&i| i >= self.envs.len()) {
            return Err(PyValueError::new_err(format!(
                "environment {index} does not exist ({} environments)",
                self.envs.len()
            )));
        }
        let source = ReferenceSource::Fixed(Arc::new(reference_of(
            reference,
            self.dt_s,
            self.task.observation.lookahead_steps,
        )?));
        let indices = index.map_or(0..self.envs.len(), |i| i..i + 1);
        for i in indices {
            self.envs.set_reference_source(i, source.clone()).map_err(value_error)?;
        }
        self.observations(py)
    }

    /// The reference environment `index` flies now, as [rows, 3] positions (m) at the control rate.
    fn reference_points<'py>(&self, py: Python<'py>, index: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let env = self
            .envs
            .envs()
            .get(index)
            .ok_or_else(|| PyValueError::new_err(format!("environment {index} does not exist")))?;
        let flat: Vec<f64> = env.reference().points().iter().flat_map(|p| [p.x, p.y, p.z]).collect();
        Ok(Array2::from_shape_vec((flat.len() / 3, 3), flat).expect("three columns").into_pyarray(py))
    }
}

fn rows<'py>(py: Python<'py>, flat: &[f32], width: usize) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let array = Array2::from_shape_vec((flat.len() / width.max(1), width), flat.to_vec()).map_err(value_error)?;
    Ok(array.into_pyarray(py))
}

/// A trained flight policy (a `policy.safetensors` from `flapper train`): its mean action.
#[pyclass(module = "flapper._flapper", frozen)]
struct Policy {
    policy: ActorCritic,
    task_toml: String,
    /// The file as read (for exports: its task and description) and where from.
    file: FlightPolicyFile,
    path: PathBuf,
}

impl Policy {
    /// The policy with the facts of its task on `model` (an MJCF file; the shipped robot if `None`).
    fn deployable(&self, model: Option<&str>) -> PyResult<DeployablePolicy> {
        let robot = match model {
            Some(path) => RobotModel::load(Path::new(path)),
            None => RobotModel::flapper(),
        }
        .map_err(value_error)?;
        DeployablePolicy::of(&self.file, &self.path, &robot).map_err(value_error)
    }
}

#[pymethods]
impl Policy {
    #[staticmethod]
    fn load(path: &str) -> PyResult<Self> {
        let file = flapper_eval::load_flight_policy_file(Path::new(path)).map_err(value_error)?;
        Ok(Self {
            policy: file.policy.clone(),
            task_toml: toml::to_string(&file.task).map_err(value_error)?,
            file,
            path: PathBuf::from(path),
        })
    }

    /// The numbers of the deterministic action, as flapper applies them in float32: a dict with
    /// `normalizer_mean`, `normalizer_scale` ([obs]; normalized = clip((x - mean) * scale, -clip, clip)),
    /// `normalizer_epsilon`, `normalizer_clip`, `layers` (a list of (weight [out, in], bias [out])) and
    /// `activation` ("elu" or "tanh", between the layers).
    fn arrays<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let arrays = PolicyArrays::of(&self.policy);
        let dict = PyDict::new(py);
        dict.set_item("normalizer_mean", arrays.normalizer_mean.clone().into_pyarray(py))?;
        dict.set_item("normalizer_scale", arrays.normalizer_scale.clone().into_pyarray(py))?;
        dict.set_item("normalizer_epsilon", arrays.normalizer_epsilon)?;
        dict.set_item("normalizer_clip", arrays.normalizer_clip)?;
        let layers = PyList::empty(py);
        for layer in &arrays.layers {
            let weight =
                Array2::from_shape_vec((layer.fan_out, layer.fan_in), layer.weight.clone()).map_err(value_error)?;
            layers.append((weight.into_pyarray(py), layer.bias.clone().into_pyarray(py)))?;
        }
        dict.set_item("layers", layers)?;
        let activation = match arrays.activation {
            flapper_ppo::mlp::Activation::Elu => "elu",
            flapper_ppo::mlp::Activation::Tanh => "tanh",
        };
        dict.set_item("activation", activation)?;
        Ok(dict)
    }

    /// What a robot must know around the policy (observation layout, joints and ranges, rates, filter
    /// cutoff, training steps) as (key, value) string pairs: the ONNX export's metadata. `model`: an
    /// MJCF file for the joint ranges (the shipped robot by default).
    #[pyo3(signature = (model=None))]
    fn deployment_metadata(&self, model: Option<&str>) -> PyResult<Vec<(String, String)>> {
        Ok(self.deployable(model)?.facts.metadata())
    }

    /// Writes the policy as ONNX (opset 17) at `path`, which must not exist: input `obs` float32
    /// [batch, obs], output `actions` float32 [batch, 5], the normalizer and the clip to [-1, 1] inside
    /// the graph, [`Policy.deployment_metadata`] as its metadata (docs/deploy.md). Needs the `onnx`
    /// package (`pip install "flapper[test]"`).
    #[pyo3(signature = (path, model=None))]
    fn export_onnx(slf: &Bound<'_, Self>, path: &str, model: Option<&str>) -> PyResult<()> {
        flapper_deploy::refuse_existing(Path::new(path)).map_err(value_error)?;
        let metadata = slf.get().deployable(model)?.facts.metadata();
        let writer = slf.py().import("flapper.onnx_export")?;
        writer.call_method1("write_onnx", (slf, path, metadata))?;
        Ok(())
    }

    #[getter]
    fn observation_size(&self) -> usize {
        self.policy.observation_size()
    }

    #[getter]
    fn action_size(&self) -> usize {
        self.policy.action_size()
    }

    /// The task the policy was trained on, as TOML.
    #[getter]
    fn task_toml(&self) -> &str {
        &self.task_toml
    }

    /// Mean actions [N, 5] (float32) for raw observations [N, obs] (float32, finite): the same bits
    /// as `flapper eval` computes, on any CPU, for a batch or one row at a time.
    fn act<'py>(
        &self,
        py: Python<'py>,
        observations: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let shape = observations.shape().to_vec();
        if shape[1] != self.policy.observation_size() {
            return Err(PyValueError::new_err(format!(
                "observations must have shape (N, {}), got {shape:?}",
                self.policy.observation_size()
            )));
        }
        let flat: Vec<f32> = observations.as_array().iter().copied().collect();
        if flat.iter().any(|x| !x.is_finite()) {
            return Err(PyValueError::new_err("observations must be finite"));
        }
        let policy = &self.policy;
        let actions = py.detach(|| {
            let (mut scratch, mut actions) = (InferenceScratch::default(), Vec::new());
            policy.act_deterministic(&flat, &mut scratch, &mut actions);
            actions
        });
        rows(py, &actions, self.policy.action_size())
    }
}

/// The named references: (name, description) pairs.
#[pyfunction]
fn reference_names() -> Vec<(&'static str, &'static str)> {
    NAMED_REFERENCES.to_vec()
}

/// Where the named references start (m).
#[pyfunction]
fn named_reference_start_m() -> (f64, f64, f64) {
    (NAMED_START_M.x, NAMED_START_M.y, NAMED_START_M.z)
}

/// Environment steps per second of the Rust `FlightVecEnv` alone (no Python between steps): stage
/// `stage`, `num_envs` environments, `steps` steps with the same `actions` [num_envs, 5] each step.
/// The baseline of `benchmarks/steps_per_second.py`.
#[pyfunction]
#[pyo3(signature = (actions, steps, stage=1, seed=0, threads=0))]
fn rust_steps_per_second(
    py: Python<'_>,
    actions: PyReadonlyArray2<'_, f32>,
    steps: usize,
    stage: i64,
    seed: u64,
    threads: usize,
) -> PyResult<f64> {
    let (count, flat): (usize, Vec<f32>) = (actions.shape()[0], actions.as_array().iter().copied().collect());
    if actions.shape()[1] != ACTION_SIZE || count == 0 || flat.iter().any(|a| !a.is_finite()) {
        return Err(PyValueError::new_err("actions must be finite, of shape (num_envs, 5)"));
    }
    let robot = RobotModel::flapper().map_err(value_error)?;
    let task = TaskConfig::stage(stage).map_err(value_error)?;
    py.detach(move || {
        let mut envs = FlightVecEnv::new(&robot, task, ReferenceSource::Procedural, count, seed, threads)?;
        let began = std::time::Instant::now();
        for _ in 0..steps {
            envs.step(&flat)?;
            envs.take_finished_episodes();
        }
        Ok((steps * count) as f64 / began.elapsed().as_secs_f64())
    })
    .map_err(|e: flapper_sim::ModelError| value_error(e))
}

#[pymodule]
fn _flapper(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<VecEnvCore>()?;
    m.add_class::<Policy>()?;
    m.add_function(wrap_pyfunction!(reference_names, m)?)?;
    m.add_function(wrap_pyfunction!(named_reference_start_m, m)?)?;
    m.add_function(wrap_pyfunction!(rust_steps_per_second, m)?)?;
    Ok(())
}
