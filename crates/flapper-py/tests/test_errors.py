"""Bad input from Python raises an exception carrying flapper's message, never crashes."""

import numpy as np
import pytest

import flapper


@pytest.fixture
def env():
    return flapper.FlightVectorEnv(2, stage=1, seed=0)


def test_bad_actions(env):
    with pytest.raises(ValueError, match=r"shape \(2, 5\)"):
        env.step(np.zeros((2, 4), np.float32))
    with pytest.raises(ValueError, match=r"shape \(2, 5\)"):
        env.step(np.zeros((3, 5), np.float32))
    with pytest.raises(TypeError, match="floating point"):
        env.step(np.zeros((2, 5), np.int64))
    with pytest.raises(TypeError, match="floating point"):
        env.step([["a"] * 5] * 2)
    bad = np.zeros((2, 5), np.float32)
    bad[1, 3] = np.nan
    with pytest.raises(ValueError, match="action 3 of environment 1 is NaN"):
        env.step(bad)
    bad[1, 3] = np.inf
    with pytest.raises(ValueError, match="finite"):
        env.step(bad)
    # float64 is converted; the environment still works after the errors.
    env.step(np.zeros((2, 5)))


def test_bad_task_choices(tmp_path):
    with pytest.raises(ValueError, match="stage"):
        flapper.FlightVectorEnv(2, stage=7)
    with pytest.raises(TypeError, match="stage"):
        flapper.FlightVectorEnv(2, stage="two")
    with pytest.raises(ValueError, match="one of stage, config or policy"):
        flapper.FlightVectorEnv(2, stage=1, config="configs/stage1.toml")
    with pytest.raises(ValueError, match="num_envs"):
        flapper.FlightVectorEnv(0)
    with pytest.raises(ValueError, match="missing.toml"):
        flapper.FlightVectorEnv(2, config=tmp_path / "missing.toml")
    broken = tmp_path / "broken.toml"
    broken.write_text("[ppo]\nlearning_rate = -1.0\n")
    with pytest.raises(ValueError, match="learning_rate"):
        flapper.FlightVectorEnv(2, config=broken)
    nonsense = tmp_path / "nonsense.toml"
    nonsense.write_text("[task.episode]\nmax_steps = 'many'\n")
    with pytest.raises(ValueError, match="nonsense.toml"):
        flapper.FlightVectorEnv(2, config=nonsense)
    with pytest.raises(ValueError, match="evaluation=True"):
        flapper.FlightVectorEnv(2, evaluation=True)


def test_bad_references(env):
    with pytest.raises(ValueError, match="unknown reference 'nowhere'"):
        env.set_reference("nowhere")
    with pytest.raises(ValueError, match="3 columns"):
        env.set_reference(np.zeros((100, 2)))
    points = np.zeros((100, 3))
    points[40, 1] = np.nan
    with pytest.raises(ValueError, match="row 40"):
        env.set_reference(points)
    points[40, 1] = 100.0
    with pytest.raises(ValueError, match="row 40: speed"):
        env.set_reference(points)
    with pytest.raises(ValueError, match="rows"):
        env.set_reference(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="environment 5 does not exist"):
        env.set_reference("cruise", env_index=5)
    with pytest.raises(TypeError, match="a reference is"):
        env.set_reference(42)


def test_bad_policies(root, tmp_path):
    with pytest.raises(ValueError, match="nothing.safetensors"):
        flapper.Policy.load(str(tmp_path / "nothing.safetensors"))
    junk = tmp_path / "junk.safetensors"
    junk.write_bytes(b"\x00" * 64)
    with pytest.raises(ValueError, match="junk.safetensors"):
        flapper.Policy.load(str(junk))
    policy = flapper.Policy.load(str(root / "policies/history/stage1/policy.safetensors"))
    with pytest.raises(ValueError, match="540"):
        policy.act(np.zeros((2, 100), np.float32))
    with pytest.raises(ValueError, match="finite"):
        policy.act(np.full((1, 540), np.nan, np.float32))
