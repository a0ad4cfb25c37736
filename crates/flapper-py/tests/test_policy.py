"""A shipped policy flown through the binding reproduces `flapper eval`."""

import csv

import numpy as np

import flapper
from conftest import cargo_run


def fly(policy_path, reference, episodes, seed):
    """Each environment's first episode, as `flapper eval` flies episode k: completion and RMS error."""
    policy = flapper.Policy.load(policy_path)
    env = flapper.FlightVectorEnv(episodes, policy=policy_path, reference=reference, evaluation=True, seed=seed)
    obs, _ = env.reset(seed=seed)
    squared, steps = np.zeros(episodes), np.zeros(episodes, int)
    outcome = [None] * episodes
    while any(o is None for o in outcome):
        # One row at a time, as flapper eval: a batched product may round differently in the last
        # bit, and a flight amplifies that.
        actions = np.concatenate([policy.act(obs[k : k + 1]) for k in range(episodes)])
        obs, _, terminated, truncated, info = env.step(actions)
        flying = np.array([o is None for o in outcome])
        error = info["position_error_m"].astype(np.float64)
        squared[flying] += error[flying] ** 2
        steps[flying] += 1
        for k in np.flatnonzero(flying & (terminated | truncated)):
            outcome[k] = info["episode"]["end"][k]
    rms = np.sqrt(squared / steps)
    completed = np.array([o in ("time_limit", "reference_end") for o in outcome])
    return completed, rms


def test_shipped_stage_3_policy_reproduces_flapper_eval(root, tmp_path):
    policy, reference, episodes, seed = root / "policies/stage3/policy.safetensors", "lateral", 4, 11
    completed, rms = fly(str(policy), reference, episodes, seed)
    cargo_run("flapper-cli", [], ["eval", "--policy", policy, "--reference", reference, "--episodes", episodes,
                                  "--seed", seed, "--no-baseline", "--out", tmp_path])
    errors = {}
    with open(tmp_path / "policy" / "steps.csv") as f:
        for row in csv.DictReader(f):
            errors.setdefault(int(row["episode"]), []).append(float(row["error_m"]))
    eval_rms = np.array([np.sqrt(np.mean(np.square(errors[k]))) for k in range(episodes)])
    assert completed.all()
    # The binding reports errors in float32; flapper eval writes them rounded in its CSV.
    np.testing.assert_allclose(rms, eval_rms, rtol=1e-3)
    assert np.all(rms < 1.0)


def test_policy_mean_action(root):
    policy = flapper.Policy.load(str(root / "policies/stage2/policy.safetensors"))
    assert policy.observation_size == 540 and policy.action_size == 5
    assert "[episode]" in policy.task_toml
    env = flapper.FlightVectorEnv(3, policy=str(root / "policies/stage2/policy.safetensors"), seed=4)
    obs, _ = env.reset(seed=4)
    actions = policy.act(obs)
    assert actions.shape == (3, 5) and actions.dtype == np.float32
    assert np.array_equal(actions, policy.act(obs)), "the mean action is deterministic"
    # Rows are independent; a different batch size may round differently in the last bits.
    np.testing.assert_allclose(actions[1:2], policy.act(obs[1:2]), rtol=0, atol=1e-5)
