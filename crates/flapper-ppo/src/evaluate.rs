//! Running a policy without exploration noise (its mean action, normalizer frozen) until a number of
//! episodes have finished: the learner's own check of what it learned.

use crate::actor_critic::{ActorCritic, InferenceScratch};
use crate::vec_env::{EnvError, EpisodeRecord, VecEnv};

/// Steps `env` with the policy's mean actions until `episodes` episodes finished (or `max_steps`
/// batched steps passed); returns the first `episodes` of them.
pub fn evaluate_mean_policy<E: VecEnv>(
    policy: &ActorCritic,
    env: &mut E,
    episodes: usize,
    max_steps: usize,
) -> Result<Vec<EpisodeRecord<E::EndReason>>, EnvError> {
    let mut scratch = InferenceScratch::default();
    let mut actions = Vec::new();
    let mut finished = Vec::new();
    for _ in 0..max_steps {
        if finished.len() >= episodes {
            break;
        }
        policy.act_deterministic(env.observations(), &mut scratch, &mut actions);
        env.step(&actions)?;
        finished.extend(env.take_finished_episodes());
    }
    finished.truncate(episodes);
    Ok(finished)
}
