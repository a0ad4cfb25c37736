"""`FlightVectorEnv`: N flight environments as one `gymnasium.vector.VectorEnv`."""

import numpy as np
import gymnasium
from gymnasium.spaces import Box
from gymnasium.vector.utils import batch_space
from gymnasium.vector import AutoresetMode

from ._flapper import VecEnvCore

REWARD_TERMS = ("position", "body_rate", "level", "energy", "action_rate")


class FlightVectorEnv(gymnasium.vector.VectorEnv):
    """N flight environments stepped in parallel by flapper's Rust code (the GIL is released while
    they step). Same seed, same numbers as flapper's own `FlightVecEnv`.

    The task comes from one of `stage` (1-4, the curriculum presets), `config` (a run config TOML,
    as `flapper train --config`) or `policy` (a policy file: the task it was trained on); none
    means stage 1. `reference` (a name from `flapper.reference_names()`, a CSV path, or a float64
    array of x, y, z rows at the 50 Hz control rate) makes every environment fly that path instead of
    the curriculum's random ones; `evaluation=True` then sets the task up as `flapper eval` does
    (no randomization, episodes as long as the reference, only the 3 m rule ends them early).

    Autoreset: `AutoresetMode.SAME_STEP`, as flapper's own environments. When an episode ends in
    `step`, the environment starts its next episode at once and the returned observation row is that
    episode's first; the ended episode's last observation is in `info["final_obs"]` (rows where
    `info["_final_obs"]` is true), and its return, length and end in `info["episode"]`.

    `info` also carries every step: `reward_terms` (the five kernel values, unweighted),
    `position_error_m` (distance to the target after the step).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}

    def __init__(self, num_envs, stage=None, config=None, policy=None, reference=None, evaluation=False, seed=0, threads=0):
        if stage is not None and not isinstance(stage, (int, np.integer)):
            raise TypeError(f"stage must be an integer 1-4, got {stage!r}")
        if isinstance(reference, np.ndarray):
            reference = np.ascontiguousarray(reference, dtype=np.float64)
        self._core = VecEnvCore(
            int(num_envs),
            stage=None if stage is None else int(stage),
            config=None if config is None else str(config),
            policy=None if policy is None else str(policy),
            reference=reference,
            evaluation=bool(evaluation),
            seed=int(seed),
            threads=int(threads),
        )
        self.num_envs = self._core.num_envs
        self.single_observation_space = Box(-np.inf, np.inf, (self._core.observation_size,), np.float32)
        self.single_action_space = Box(-1.0, 1.0, (self._core.action_size,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.render_mode = None
        self.dt = self._core.dt_s
        self.max_episode_steps = self._core.max_episode_steps

    def reset(self, *, seed=None, options=None):
        """With `seed`, every environment starts exactly as in a new batch built with that seed;
        without, each continues its own random stream. Returns (observations [N, obs], {})."""
        super().reset(seed=seed)
        if options:
            raise ValueError(f"FlightVectorEnv.reset takes no options, got {sorted(options)}")
        return self._core.reset(seed), {}

    def step(self, actions):
        actions = np.asarray(actions)
        if actions.dtype.kind != "f":
            raise TypeError(f"actions must be floating point (float32), got dtype {actions.dtype}")
        actions = np.ascontiguousarray(actions, dtype=np.float32)
        if actions.shape != self.action_space.shape:
            raise ValueError(f"actions must have shape {self.action_space.shape}, got {actions.shape}")
        out = self._core.step(actions)
        terminated, truncated = out["terminated"], out["truncated"]
        everyone = np.ones(self.num_envs, dtype=bool)
        info = {
            "reward_terms": {name: out["reward_" + name] for name in REWARD_TERMS},
            "_reward_terms": everyone,
            "position_error_m": out["position_error_m"],
            "_position_error_m": everyone,
        }
        ended = terminated | truncated
        if ended.any():
            info["final_obs"] = out["final_observations"]
            info["_final_obs"] = ended
            info["episode"] = {
                "r": out["episode_return"],
                "l": out["episode_length"],
                "end": np.array(out["end_reason"]),
                "_r": ended,
                "_l": ended,
                "_end": ended,
            }
            info["_episode"] = ended
        return out["observations"], out["rewards"], terminated, truncated, info

    def set_reference(self, reference, env_index=None):
        """Environment `env_index` (all when None) flies `reference` (a name, a CSV path, or a
        float64 [rows, 3] array at the control rate) from now on and starts a new episode on it.
        Returns the observations [N, obs]."""
        if isinstance(reference, np.ndarray):
            reference = np.ascontiguousarray(reference, dtype=np.float64)
        return self._core.set_reference(reference, None if env_index is None else int(env_index))

    def reference_points(self, env_index=0):
        """The path environment `env_index` flies now: [rows, 3] positions (m) at the control rate."""
        return self._core.reference_points(int(env_index))

    @property
    def task_toml(self):
        """The task's settings as TOML."""
        return self._core.task_toml
