//! A known-answer check for the learner: Gymnasium's InvertedPendulum (v5) as a vectorized
//! environment. Observation (cart position, pole angle, cart velocity, pole angular velocity),
//! action = motor control clipped to +-3, two 0.02 s RK4 steps per action, reward 1 per step while
//! the pole is within 0.2 rad of upright (0 at the step it falls, which ends the episode), episodes
//! cut at 1000 steps, start at rest plus U(-0.01, 0.01) on every coordinate. The best return is 1000.

use mujoco_rs::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use flapper_ppo::{EndReason, EnvError, EpisodeRecord, VecEnv};

/// The MJCF of `models/inverted_pendulum.xml`, compiled in.
pub const INVERTED_PENDULUM_MJCF: &str = include_str!("../../../models/inverted_pendulum.xml");

/// Episode cap, as Gymnasium's time limit.
pub const MAX_EPISODE_STEPS: usize = 1000;
/// Simulation steps per action (Gymnasium's frame skip).
const FRAME_SKIP: usize = 2;
/// The pole has fallen beyond this angle.
const FALLEN_RAD: f64 = 0.2;
const RESET_NOISE: f64 = 0.01;
const OBSERVATION_SIZE: usize = 4;

/// How a pendulum episode ends.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PendulumEnd {
    /// The pole leaned past [`FALLEN_RAD`] (terminated).
    PoleFell,
    /// [`MAX_EPISODE_STEPS`] reached (truncated).
    TimeLimit,
}

impl EndReason for PendulumEnd {
    const ALL: &'static [Self] = &[Self::PoleFell, Self::TimeLimit];

    fn name(self) -> &'static str {
        match self {
            Self::PoleFell => "pole_fell",
            Self::TimeLimit => "time_limit",
        }
    }
}

struct Pendulum {
    data: MjData<Box<MjModel>>,
    rng: ChaCha8Rng,
    steps: usize,
    episode_return: f64,
}

impl Pendulum {
    fn reset(&mut self) {
        self.data.reset();
        for q in self.data.qpos_mut() {
            *q += self.rng.random_range(-RESET_NOISE..=RESET_NOISE);
        }
        for v in self.data.qvel_mut() {
            *v += self.rng.random_range(-RESET_NOISE..=RESET_NOISE);
        }
        self.data.forward();
        self.steps = 0;
        self.episode_return = 0.0;
    }

    fn observe(&self, out: &mut [f32]) {
        let (q, v) = (self.data.qpos(), self.data.qvel());
        for (o, x) in out.iter_mut().zip(q.iter().chain(v.iter())) {
            *o = *x as f32;
        }
    }
}

/// N inverted pendulums with automatic reset.
pub struct InvertedPendulumEnvs {
    envs: Vec<Pendulum>,
    observations: Vec<f32>,
    final_observations: Vec<f32>,
    rewards: Vec<f32>,
    terminated: Vec<bool>,
    truncated: Vec<bool>,
    finished: Vec<EpisodeRecord<PendulumEnd>>,
}

impl InvertedPendulumEnvs {
    pub fn new(count: usize, seed: u64) -> Result<Self, EnvError> {
        let model =
            MjModel::from_xml_string(INVERTED_PENDULUM_MJCF).map_err(|e| format!("inverted pendulum model: {e}"))?;
        let envs = (0..count)
            .map(|_| {
                let data =
                    MjData::try_new(Box::new(model.clone())).map_err(|e| format!("inverted pendulum data: {e}"))?;
                Ok(Pendulum { data, rng: ChaCha8Rng::seed_from_u64(0), steps: 0, episode_return: 0.0 })
            })
            .collect::<Result<Vec<_>, EnvError>>()?;
        let mut vec_env = Self {
            envs,
            observations: vec![0.0; count * OBSERVATION_SIZE],
            final_observations: vec![0.0; count * OBSERVATION_SIZE],
            rewards: vec![0.0; count],
            terminated: vec![false; count],
            truncated: vec![false; count],
            finished: Vec::new(),
        };
        vec_env.seed_streams(seed);
        Ok(vec_env)
    }

    /// Gives every pendulum its own random stream from (`seed`, its index) and starts an episode.
    fn seed_streams(&mut self, seed: u64) {
        for (i, env) in self.envs.iter_mut().enumerate() {
            env.rng = ChaCha8Rng::seed_from_u64(seed);
            env.rng.set_stream(i as u64);
            env.reset();
            env.observe(&mut self.observations[i * OBSERVATION_SIZE..(i + 1) * OBSERVATION_SIZE]);
        }
        self.finished.clear();
    }
}

/// One pendulum mid-episode: MuJoCo's integration state, the random stream, the episode so far.
#[derive(serde::Serialize, serde::Deserialize)]
struct PendulumSnapshot {
    physics: Vec<f64>,
    rng: ChaCha8Rng,
    steps: usize,
    episode_return: f64,
}

impl VecEnv for InvertedPendulumEnvs {
    type EndReason = PendulumEnd;

    fn num_envs(&self) -> usize {
        self.envs.len()
    }

    fn observation_size(&self) -> usize {
        OBSERVATION_SIZE
    }

    fn action_size(&self) -> usize {
        1
    }

    fn step(&mut self, actions: &[f32]) -> Result<(), EnvError> {
        assert_eq!(actions.len(), self.envs.len());
        for (i, env) in self.envs.iter_mut().enumerate() {
            let action = if actions[i].is_finite() { (actions[i] as f64).clamp(-3.0, 3.0) } else { 0.0 };
            env.data.ctrl_mut()[0] = action;
            for _ in 0..FRAME_SKIP {
                env.data.step();
            }
            env.steps += 1;
            let state_finite = env.data.qpos().iter().chain(env.data.qvel().iter()).all(|x| x.is_finite());
            let fell = !state_finite || env.data.qpos()[1].abs() > FALLEN_RAD;
            let reward = if fell { 0.0 } else { 1.0 };
            env.episode_return += reward;
            let cut = !fell && env.steps >= MAX_EPISODE_STEPS;
            self.rewards[i] = reward as f32;
            self.terminated[i] = fell;
            self.truncated[i] = cut;
            let out = &mut self.observations[i * OBSERVATION_SIZE..(i + 1) * OBSERVATION_SIZE];
            if fell || cut {
                self.finished.push(EpisodeRecord {
                    episode_return: env.episode_return,
                    length: env.steps,
                    end: if fell { PendulumEnd::PoleFell } else { PendulumEnd::TimeLimit },
                });
                env.observe(&mut self.final_observations[i * OBSERVATION_SIZE..(i + 1) * OBSERVATION_SIZE]);
                env.reset();
            }
            env.observe(out);
        }
        Ok(())
    }

    fn observations(&self) -> &[f32] {
        &self.observations
    }

    fn rewards(&self) -> &[f32] {
        &self.rewards
    }

    fn terminated(&self) -> &[bool] {
        &self.terminated
    }

    fn truncated(&self) -> &[bool] {
        &self.truncated
    }

    fn final_observations(&self) -> &[f32] {
        &self.final_observations
    }

    fn take_finished_episodes(&mut self) -> Vec<EpisodeRecord<PendulumEnd>> {
        std::mem::take(&mut self.finished)
    }

    fn save_state(&self) -> Result<Vec<u8>, EnvError> {
        let snapshots: Vec<PendulumSnapshot> = self
            .envs
            .iter()
            .map(|env| PendulumSnapshot {
                physics: env.data.state(MjtState::mjSTATE_INTEGRATION as u32).into_vec(),
                rng: env.rng.clone(),
                steps: env.steps,
                episode_return: env.episode_return,
            })
            .collect();
        Ok(serde_json::to_vec(&snapshots)?)
    }

    fn restore_state(&mut self, state: &[u8]) -> Result<(), EnvError> {
        let snapshots: Vec<PendulumSnapshot> = serde_json::from_slice(state)?;
        if snapshots.len() != self.envs.len() {
            return Err(
                format!("saved state holds {} pendulums, this batch {}", snapshots.len(), self.envs.len()).into()
            );
        }
        for (i, (env, saved)) in self.envs.iter_mut().zip(snapshots).enumerate() {
            env.data
                .set_state(&saved.physics, MjtState::mjSTATE_INTEGRATION as u32)
                .map_err(|e| format!("pendulum state: {e}"))?;
            env.data.forward();
            env.rng = saved.rng;
            env.steps = saved.steps;
            env.episode_return = saved.episode_return;
            env.observe(&mut self.observations[i * OBSERVATION_SIZE..(i + 1) * OBSERVATION_SIZE]);
        }
        self.finished.clear();
        Ok(())
    }
}
