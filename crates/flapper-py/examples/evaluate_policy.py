"""Fly a shipped policy through the Python binding, as `flapper eval` does (same starts, same
numbers): completion (within 3 m to the end of the reference) and RMS tracking error per episode.

    python crates/flapper-py/examples/evaluate_policy.py [--policy policies/final/policy.safetensors]
        [--reference lateral] [--episodes 10] [--seed 11]
"""

import argparse

import numpy as np

import flapper


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--policy", default="policies/final/policy.safetensors", help="default: the final controller")
    parser.add_argument("--reference", default="lateral", help="a name (see below) or a CSV of time_s,x_m,y_m,z_m")
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--seed", type=int, default=11)
    args = parser.parse_args()

    policy = flapper.Policy.load(args.policy)
    env = flapper.FlightVectorEnv(args.episodes, policy=args.policy, reference=args.reference, evaluation=True, seed=args.seed)
    obs, _ = env.reset(seed=args.seed)
    squared, steps = np.zeros(args.episodes), np.zeros(args.episodes, int)
    ends = [None] * args.episodes
    while None in ends:
        actions = policy.act(obs)  # the same bits as `flapper eval`, on any CPU
        obs, _, terminated, truncated, info = env.step(actions)
        flying = np.array([end is None for end in ends])
        squared[flying] += info["position_error_m"][flying].astype(np.float64) ** 2
        steps[flying] += 1
        for k in np.flatnonzero(flying & (terminated | truncated)):
            ends[k] = str(info["episode"]["end"][k])
    rms = np.sqrt(squared / steps)
    completed = [end in ("time_limit", "reference_end") for end in ends]
    for k in range(args.episodes):
        print(f"episode {k:3d}: {ends[k]:14s} {steps[k] * env.dt:6.2f} s  RMS {rms[k]:.3f} m")
    print(f"{args.reference}: {sum(completed)}/{args.episodes} completed, mean RMS {rms[completed].mean():.3f} m")
    print("named references:", ", ".join(name for name, _ in flapper.reference_names()))


if __name__ == "__main__":
    main()
