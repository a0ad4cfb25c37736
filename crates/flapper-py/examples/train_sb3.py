"""Train stage 1 (forward flight) for a few iterations with Stable-Baselines3's PPO on flapper's
environments: a template for trying your own algorithm on this robot.

    pip install stable-baselines3      # brings torch; not needed by flapper or its tests
    python crates/flapper-py/examples/train_sb3.py [--envs 256] [--iterations 5]

SB3 has its own vector-environment interface; `Sb3FlightEnvs` adapts `flapper.FlightVectorEnv` to
it (SB3 expects the final observation in `infos[i]["terminal_observation"]` and truncation in
`"TimeLimit.truncated"`, which flapper's same-step autoreset gives directly).
"""

import argparse

import numpy as np
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecEnv

import flapper


class Sb3FlightEnvs(VecEnv):
    def __init__(self, env, seed=0):
        self.env, self._next_seed = env, seed
        super().__init__(env.num_envs, env.single_observation_space, env.single_action_space)

    def reset(self):
        obs, _ = self.env.reset(seed=self._next_seed)
        self._next_seed = None
        return obs

    def step_async(self, actions):
        self._actions = np.asarray(actions, dtype=np.float32)

    def step_wait(self):
        obs, rewards, terminated, truncated, info = self.env.step(self._actions)
        dones = terminated | truncated
        infos = [{} for _ in range(self.num_envs)]
        for i in np.flatnonzero(dones):
            infos[i]["terminal_observation"] = info["final_obs"][i]
            infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
            infos[i]["episode"] = {"r": float(info["episode"]["r"][i]), "l": int(info["episode"]["l"][i])}
        return obs, rewards, dones, infos

    def close(self):
        pass

    def get_attr(self, attr_name, indices=None):
        return [getattr(self.env, attr_name)] * len(self._get_indices(indices))

    def set_attr(self, attr_name, value, indices=None):
        raise NotImplementedError("flapper's environments have no per-environment attributes to set")

    def env_method(self, method_name, *args, indices=None, **kwargs):
        raise NotImplementedError("call methods on FlightVectorEnv directly")

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False] * len(self._get_indices(indices))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, default=256)
    parser.add_argument("--iterations", type=int, default=5, help="PPO iterations of 24 steps per environment")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    envs = Sb3FlightEnvs(flapper.FlightVectorEnv(args.envs, stage=1, seed=args.seed), seed=args.seed)
    # rsl_rl-like settings, as flapper's own learner: 24 steps per environment per iteration.
    model = PPO("MlpPolicy", envs, n_steps=24, batch_size=args.envs * 24 // 4, n_epochs=5, learning_rate=1e-3,
                gamma=0.99, gae_lambda=0.95, clip_range=0.2, policy_kwargs={"net_arch": [512, 256, 128]},
                seed=args.seed, verbose=1, device="cpu")
    model.learn(total_timesteps=args.iterations * args.envs * 24)
    model.save("sb3_stage1")
    print("saved sb3_stage1.zip")


if __name__ == "__main__":
    main()
