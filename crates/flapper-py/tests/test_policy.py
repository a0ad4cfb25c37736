"""A shipped policy flown through the binding reproduces `flapper eval`."""

import csv
import json

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
        actions = policy.act(obs)  # the whole batch: the same bits as one row at a time
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


def test_shipped_policy_reproduces_flapper_eval_bit_for_bit(root, tmp_path):
    policy, reference, episodes, seed = root / "policies/history/stage4/policy.safetensors", "lateral", 4, 11
    completed, rms = fly(str(policy), reference, episodes, seed)
    cargo_run("flapper-cli", [], ["eval", "--policy", policy, "--reference", reference, "--episodes", episodes,
                                  "--seed", seed, "--no-baseline", "--observations", "--out", tmp_path])
    errors = {}
    with open(tmp_path / "policy" / "steps.csv") as f:
        for row in csv.DictReader(f):
            errors.setdefault(int(row["episode"]), []).append(float(row["error_m"]))
    eval_rms = np.array([np.sqrt(np.mean(np.square(errors[k]))) for k in range(episodes)])
    assert completed.all()
    # The binding reports errors in float32; flapper eval writes them rounded in its CSV.
    np.testing.assert_allclose(rms, eval_rms, rtol=1e-3)
    assert np.all(rms < 1.0)

    # Episode 0 step by step: the observations the binding's environment gives and the actions its
    # policy takes are exactly those `flapper eval` recorded (its CSV holds round-trip decimals).
    with open(tmp_path / "policy" / "observations.csv") as f:
        recorded = np.array([[np.float32(v) for v in row[1:]] for row in list(csv.reader(f))[1:]])
    size = flapper.Policy.load(str(policy)).observation_size
    eval_obs, eval_actions = recorded[:, :size], recorded[:, size:]
    env = flapper.FlightVectorEnv(1, policy=str(policy), reference=reference, evaluation=True, seed=seed)
    obs, _ = env.reset(seed=seed)
    loaded = flapper.Policy.load(str(policy))
    for step in range(len(recorded)):
        actions = loaded.act(obs)
        assert np.array_equal(obs[0].view(np.uint32), eval_obs[step].view(np.uint32)), f"observation at step {step}"
        assert np.array_equal(actions[0].view(np.uint32), eval_actions[step].view(np.uint32)), f"action at step {step}"
        obs, _, terminated, truncated, _ = env.step(actions)
        if terminated[0] or truncated[0]:
            break


def test_golden_actions_bit_for_bit(root):
    """The golden set of crates/flapper-eval/tests/data (see its test): the binding gives the same bits."""
    data = (root / "crates/flapper-eval/tests/data/inference_golden.safetensors").read_bytes()
    header_size = int.from_bytes(data[:8], "little")
    header = json.loads(data[8 : 8 + header_size])
    body = data[8 + header_size :]

    def tensor(name):
        start, end = header[name]["data_offsets"]
        return np.frombuffer(body[start:end], dtype="<f4").reshape(header[name]["shape"])

    policy = flapper.Policy.load(str(root / header["__metadata__"]["policy"]))
    observations, golden = tensor("observations"), tensor("actions")
    assert np.array_equal(policy.act(observations).view(np.uint32), golden.view(np.uint32))
    alone = np.concatenate([policy.act(observations[k : k + 1]) for k in range(0, len(observations), 7)])
    assert np.array_equal(alone.view(np.uint32), golden[::7].view(np.uint32))


def test_policy_mean_action(root):
    policy = flapper.Policy.load(str(root / "policies/history/stage2/policy.safetensors"))
    assert policy.observation_size == 540 and policy.action_size == 5
    assert "[episode]" in policy.task_toml
    env = flapper.FlightVectorEnv(3, policy=str(root / "policies/history/stage2/policy.safetensors"), seed=4)
    obs, _ = env.reset(seed=4)
    actions = policy.act(obs)
    assert actions.shape == (3, 5) and actions.dtype == np.float32
    assert np.array_equal(actions, policy.act(obs)), "the mean action is deterministic"
    assert np.array_equal(actions[1:2], policy.act(obs[1:2])), "a row alone gives the bits it gives in a batch"
