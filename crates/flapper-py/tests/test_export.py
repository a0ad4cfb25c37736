"""The policy leaving flapper (docs/deploy.md): the ONNX export is a valid model whose onnxruntime actions are
flapper's on a real flight, the command line writes the same file and refuses bad input with one line, and
the worked example flies it in stock MuJoCo as flapper eval does."""

import importlib.util
import json
import re
import subprocess

import numpy as np
import onnx
import onnxruntime
import pytest

import flapper
from conftest import ROOT, cargo_run

FINAL = "policies/final/policy.safetensors"


def flapper_cli(args):
    """The flapper command (release build); its completed process, whatever its exit code."""
    command = ["cargo", "run", "--release", "--quiet", "-p", "flapper-cli", "--", *map(str, args)]
    return subprocess.run(command, cwd=ROOT, capture_output=True, text=True)


@pytest.fixture(scope="module")
def flight():
    """Observations of a real flight: the final controller on `longitudinal` from flapper eval's episode 0
    start (seed 11), through the binding (which reproduces flapper eval bit for bit)."""
    path = str(ROOT / FINAL)
    policy = flapper.Policy.load(path)
    env = flapper.FlightVectorEnv(1, policy=path, reference="longitudinal", evaluation=True, seed=11)
    obs, _ = env.reset(seed=11)
    rows = []
    while True:
        rows.append(obs[0].copy())
        obs, _, terminated, truncated, _ = env.step(policy.act(obs))
        if terminated[0] or truncated[0]:
            return np.array(rows)


def test_onnx_export_is_valid_and_gives_flappers_actions_on_a_real_flight(flight, tmp_path):
    policy = flapper.Policy.load(str(ROOT / FINAL))
    path = tmp_path / "policy.onnx"
    policy.export_onnx(str(path))
    model = onnx.load(str(path))
    onnx.checker.check_model(model, full_check=True)
    assert model.opset_import[0].version >= 17
    (obs,), (actions,) = model.graph.input, model.graph.output
    dims = lambda value: [d.dim_param or d.dim_value for d in value.type.tensor_type.shape.dim]  # noqa: E731
    assert (obs.name, dims(obs), actions.name, dims(actions)) == ("obs", ["batch", 540], "actions", ["batch", 5])
    ops = [node.op_type for node in model.graph.node]
    assert ops[:3] == ["Sub", "Mul", "Clip"], "the normalizer as explicit nodes"
    assert ops.count("Gemm") == 4 and ops.count("Elu") == 3 and ops[-1] == "Clip"

    meta = {p.key: p.value for p in model.metadata_props}
    assert meta["observation_size"] == "540" and len(json.loads(meta["observation_names"])) == 540
    assert json.loads(meta["joint_names"]) == ["flap_left", "pitch_left", "flap_right", "pitch_right", "tail_pitch"]
    assert np.allclose(np.degrees(json.loads(meta["joint_ranges_rad"])), [[-60, 60], [-45, 45], [-60, 60], [-45, 45], [-40, 40]])
    assert float(meta["control_rate_hz"]) == 50.0 and float(meta["filter_cutoff_hz"]) == 7.0
    # The facts of the policy file itself (its .json beside it, written by training).
    facts = json.loads((ROOT / (FINAL + ".json")).read_text())
    # The final controller's last two stages trained with passive feathering: the twist travels with the export.
    trained_twist = float(re.search(r"\npassive_feathering_s = (\S+)\n", facts["config_toml"]).group(1))
    assert float(meta["passive_feathering_s"]) == trained_twist == 0.01
    assert meta["training_env_steps"] == str(facts["env_steps"]) and meta["source_kind"] == "policy"

    session = onnxruntime.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    expected = np.clip(policy.act(flight), -1.0, 1.0)
    batch = session.run(["actions"], {"obs": flight})[0]
    one = np.concatenate([session.run(["actions"], {"obs": flight[k : k + 1]})[0] for k in range(0, len(flight), 50)])
    difference = np.abs(batch - expected).max()
    print(f"ONNX (onnxruntime {onnxruntime.__version__}) against flapper.Policy.act on {len(flight)} observations "
          f"of a longitudinal flight: max |difference| {difference:.2e}")
    assert batch.shape == (len(flight), 5) and batch.dtype == np.float32
    assert difference < 1e-5
    assert np.abs(one - expected[::50]).max() < 1e-5, "a dynamic batch of one"
    assert (np.abs(expected) < 1).mean() > 0.25, "most actions are inside the clip, so the comparison tells"


def test_the_command_line_writes_the_same_onnx_and_refuses_bad_input_with_one_line(tmp_path):
    cli = tmp_path / "cli.onnx"
    done = flapper_cli(["export-policy", "--policy", FINAL, "--format", "onnx", "--out", cli])
    assert done.returncode == 0, done.stderr
    assert "179520 multiply-adds" in done.stdout and "724212 bytes" in done.stdout, done.stdout
    from_python = tmp_path / "python.onnx"
    flapper.Policy.load(str(ROOT / FINAL)).export_onnx(str(from_python))
    assert cli.read_bytes() == from_python.read_bytes(), "one writer: the command line calls the package"

    def refused(args, needle):
        done = flapper_cli(["export-policy", *args])
        assert done.returncode != 0 and "panicked" not in done.stderr, done.stderr
        assert len(done.stderr.strip().splitlines()) == 1 and needle in done.stderr, done.stderr

    before = cli.read_bytes()
    refused(["--policy", FINAL, "--format", "onnx", "--out", cli], "exists; choose another name")
    assert cli.read_bytes() == before, "nothing overwritten"
    (tmp_path / "notes.txt").write_text("not a policy")
    refused(["--policy", tmp_path / "notes.txt", "--format", "onnx", "--out", tmp_path / "x.onnx"], "is not a flapper policy")
    refused(["--policy", FINAL, "--format", "tflite", "--out", tmp_path / "x.tflite"], "unknown --format 'tflite'")
    with pytest.raises(ValueError, match="exists"):
        flapper.Policy.load(str(ROOT / FINAL)).export_onnx(str(cli))


def load_example():
    path = ROOT / "crates/flapper-py/examples/fly_onnx_in_mujoco.py"
    spec = importlib.util.spec_from_file_location("fly_onnx_in_mujoco", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_worked_example_flies_the_onnx_policy_in_stock_mujoco_as_flapper_eval_does(tmp_path):
    """docs/deploy.md's example, on 4 s of `longitudinal`: with flapper eval's recorded actions its
    observations are flapper's to the bit at every step; with the ONNX policy it tracks as flapper does."""
    cargo_run("flapper-cli", [], ["reference", "longitudinal", "--out", tmp_path / "reference"])
    reference_csv = tmp_path / "reference" / "reference.csv"
    cargo_run("flapper-cli", [], ["eval", "--policy", FINAL, "--reference", reference_csv, "--episodes", 1, "--seed", 11,
                                  "--no-baseline", "--observations", "--out", tmp_path / "eval"])
    onnx_path = tmp_path / "policy.onnx"
    flapper.Policy.load(str(ROOT / FINAL)).export_onnx(str(onnx_path))

    example = load_example()
    policy = example.OnnxPolicy(onnx_path)
    robot = example.Robot(ROOT / "models/flapper.xml", policy)
    reference = example.load_reference(reference_csv, robot.control_period_s)
    start, eval_observations, eval_actions, eval_errors = example.read_eval(tmp_path / "eval" / "policy", 540)
    steps = 200

    observations, _, errors = example.fly(policy, robot, reference, start, steps, recorded_actions=eval_actions)
    assert len(observations) == steps
    for k in range(steps):
        assert np.array_equal(observations[k].view(np.uint32), eval_observations[k].view(np.uint32)), f"step {k}"
    assert np.allclose(errors, eval_errors[:steps], atol=1e-4), "flapper eval's errors (its CSV: 0.1 mm)"

    observations, actions, errors = example.fly(policy, robot, reference, start, steps)
    assert len(errors) == steps and np.array_equal(observations[0], eval_observations[0])
    assert np.abs(actions[0] - np.clip(eval_actions[0], -1, 1)).max() < 1e-5
    flown, flappers = example.rms(errors), example.rms(eval_errors[:steps])
    print(f"worked example, 4 s of longitudinal: RMS {flown:.4f} m with onnxruntime, flapper eval {flappers:.4f} m")
    assert abs(flown - flappers) < 0.05 and max(errors) < 1.0


def test_the_worked_example_twists_the_wings_of_a_feathered_policy_as_flapper_does(tmp_path):
    """A policy trained with passive feathering (here one PPO iteration of the final controller with k = 0.02 s)
    exports its twist as a fact; the worked example applies it, so with flapper eval's recorded actions its
    observations are flapper's to the bit, and without the twist they are not."""
    config = tmp_path / "feathered.toml"
    config.write_text("[task]\nstage = 4\n[task.control]\npassive_feathering_s = 0.02\n")
    run = tmp_path / "run"
    cargo_run("flapper-cli", [], ["train", "--config", config, "--init-from", FINAL, "--iterations", 1, "--envs", 8, "--out", run])
    feathered = run / "policy.safetensors"
    cargo_run("flapper-cli", [], ["reference", "longitudinal", "--out", tmp_path / "reference"])
    reference_csv = tmp_path / "reference" / "reference.csv"
    cargo_run("flapper-cli", [], ["eval", "--policy", feathered, "--reference", reference_csv, "--episodes", 1, "--seed", 11,
                                  "--no-baseline", "--observations", "--out", tmp_path / "eval"])
    onnx_path = tmp_path / "policy.onnx"
    flapper.Policy.load(str(feathered)).export_onnx(str(onnx_path))

    example = load_example()
    policy = example.OnnxPolicy(onnx_path)
    assert policy.passive_feathering_s == 0.02, "the twist travels in the metadata"
    robot = example.Robot(ROOT / "models/flapper.xml", policy)
    reference = example.load_reference(reference_csv, robot.control_period_s)
    start, eval_observations, eval_actions, _ = example.read_eval(tmp_path / "eval" / "policy", 540)
    steps = 200

    def flown():
        observations, _, _ = example.fly(policy, robot, reference, start, steps, recorded_actions=eval_actions)
        same = [np.array_equal(o.view(np.uint32), e.view(np.uint32)) for o, e in zip(observations, eval_observations)]
        return len(observations), (same.index(False) if False in same else None)

    assert flown() == (steps, None), "the twisted wings fly flapper's flight to the bit"
    policy.passive_feathering_s = 0.0
    _, first_difference = flown()
    assert first_difference is not None and first_difference < 10, "without the twist the flight is another one"
