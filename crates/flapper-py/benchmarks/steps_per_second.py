"""Environment steps per second through the Python binding against the Rust vector environment
alone, same machine, same process, same actions: `make python-bench`.

    python crates/flapper-py/benchmarks/steps_per_second.py [--envs 256] [--steps 100] [--repeats 5]
"""

import argparse
import statistics
import time

import numpy as np

import flapper
from flapper._flapper import rust_steps_per_second


def python_steps_per_second(actions, steps, stage, seed, threads):
    env = flapper.FlightVectorEnv(len(actions), stage=stage, seed=seed, threads=threads)
    env.reset(seed=seed)
    began = time.perf_counter()
    for _ in range(steps):
        env.step(actions)
    return steps * len(actions) / (time.perf_counter() - began)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--envs", type=int, default=256)
    parser.add_argument("--steps", type=int, default=100, help="steps per timed run")
    parser.add_argument("--repeats", type=int, default=5, help="timed runs of each, alternating")
    parser.add_argument("--stage", type=int, default=1)
    parser.add_argument("--threads", type=int, default=0, help="0: one per core")
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (args.envs, 5)).astype(np.float32)
    rust, python = [], []
    for repeat in range(args.repeats):
        rust.append(rust_steps_per_second(actions, args.steps, stage=args.stage, seed=repeat, threads=args.threads))
        python.append(python_steps_per_second(actions, args.steps, args.stage, repeat, args.threads))
        print(f"run {repeat + 1}/{args.repeats}: Rust {rust[-1]:8.0f} steps/s   Python {python[-1]:8.0f} steps/s", flush=True)
    r, p = statistics.median(rust), statistics.median(python)
    print(f"{args.envs} environments, stage {args.stage}, {args.steps} steps x {args.repeats} runs (medians):")
    print(f"  Rust FlightVecEnv      {r:8.0f} steps/s")
    print(f"  Python FlightVectorEnv {p:8.0f} steps/s  ({100 * p / r:.1f}% of Rust)")


if __name__ == "__main__":
    main()
