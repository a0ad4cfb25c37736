"""The Gymnasium vector environment: spaces, shapes, autoreset, and exact agreement with the Rust
`FlightVecEnv` for the same seed and actions."""

import numpy as np
import gymnasium
import pytest
from gymnasium.vector import AutoresetMode

import flapper
from conftest import cargo_run


def test_spaces_and_dtypes():
    env = flapper.FlightVectorEnv(3, stage=1, seed=0)
    assert isinstance(env, gymnasium.vector.VectorEnv)
    assert env.num_envs == 3
    assert env.single_observation_space.shape == (540,)
    assert env.single_observation_space.dtype == np.float32
    assert env.single_action_space.shape == (5,)
    assert env.single_action_space.dtype == np.float32
    assert np.all(env.single_action_space.low == -1.0) and np.all(env.single_action_space.high == 1.0)
    assert env.observation_space.shape == (3, 540)
    assert env.action_space.shape == (3, 5)
    assert env.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    assert env.dt == pytest.approx(0.02)


def test_reset_and_step_shapes():
    env = flapper.FlightVectorEnv(4, stage=3, seed=1)
    obs, info = env.reset(seed=1)
    assert obs.shape == (4, 540) and obs.dtype == np.float32 and info == {}
    assert np.all(np.isfinite(obs))
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert obs.shape == (4, 540) and obs.dtype == np.float32
    assert reward.shape == (4,) and reward.dtype == np.float32
    assert terminated.shape == (4,) and terminated.dtype == np.bool_
    assert truncated.shape == (4,) and truncated.dtype == np.bool_
    assert set(info["reward_terms"]) == {"position", "body_rate", "level", "energy", "action_rate"}
    for values in info["reward_terms"].values():
        assert values.shape == (4,) and np.all((values >= 0) & (values <= 1))
    assert np.all(info["position_error_m"] >= 0)


def test_same_seed_same_numbers_and_reset_without_seed_draws_new_episodes():
    a = flapper.FlightVectorEnv(2, stage=2, seed=5)
    b = flapper.FlightVectorEnv(2, stage=2, seed=5)
    first, _ = a.reset(seed=5)
    assert np.array_equal(first, b.reset(seed=5)[0])
    assert not np.array_equal(first, a.reset(seed=6)[0])
    again, _ = a.reset(seed=5)
    assert np.array_equal(first, again), "reset(seed) starts exactly as a new batch with that seed"
    assert not np.array_equal(first, a.reset()[0]), "reset() continues each environment's stream"


def test_autoreset_is_same_step(tmp_path):
    # Five-step episodes: every environment is truncated at steps 5 and 10, and the observation
    # returned with the end is already the next episode's first.
    config = tmp_path / "short.toml"
    config.write_text("[task]\nstage = 1\n[task.episode]\nmax_steps = 5\nmax_position_error_m = 100.0\n"
                      "attitude_termination = false\n")
    env = flapper.FlightVectorEnv(3, config=config, seed=2)
    obs, _ = env.reset(seed=2)
    zero = np.zeros((3, 5), np.float32)
    ends = []
    for step in range(1, 11):
        previous = obs
        obs, _, terminated, truncated, info = env.step(zero)
        assert not terminated.any()
        if truncated.any():
            ends.append(step)
            assert truncated.all()
            assert info["_final_obs"].all() and info["final_obs"].shape == (3, 540)
            assert not np.array_equal(info["final_obs"], obs), "the final observation is not the new episode's"
            assert np.array_equal(info["episode"]["l"], [5, 5, 5])
            assert list(info["episode"]["end"]) == ["time_limit"] * 3
        else:
            assert "final_obs" not in info and not np.array_equal(previous, obs)
    assert ends == [5, 10]


def trace_actions(steps, envs):
    # Exactly representable in float32 on both sides: no rounding can differ.
    k = np.arange(steps)[:, None, None]
    i = np.arange(envs)[None, :, None]
    j = np.arange(5)[None, None, :]
    return (((7 * k + 3 * i + 5 * j) % 17 - 8) / 8).astype(np.float32)


@pytest.mark.parametrize("stage", [1, 4])
def test_exactly_the_rust_vector_environment(tmp_path, stage):
    steps, envs, seed = 120, 6, 9
    actions = trace_actions(steps, envs)
    actions.astype("<f4").tofile(tmp_path / "actions.f32")
    cargo_run("flapper-task", ["--example", "vec_env_trace"], [stage, seed, envs, 2, tmp_path / "actions.f32", tmp_path])
    rust_obs = np.fromfile(tmp_path / "observations.f32", "<f4").reshape(steps + 1, envs, -1)
    rust_rewards = np.fromfile(tmp_path / "rewards.f32", "<f4").reshape(steps, envs)
    rust_errors = np.fromfile(tmp_path / "position_errors.f32", "<f4").reshape(steps, envs)
    rust_terminated = np.fromfile(tmp_path / "terminated.u8", np.uint8).reshape(steps, envs).astype(bool)
    rust_truncated = np.fromfile(tmp_path / "truncated.u8", np.uint8).reshape(steps, envs).astype(bool)

    env = flapper.FlightVectorEnv(envs, stage=stage, seed=seed, threads=1)
    obs, _ = env.reset(seed=seed)
    assert np.array_equal(obs, rust_obs[0])
    ended = 0
    for k in range(steps):
        obs, reward, terminated, truncated, info = env.step(actions[k])
        assert np.array_equal(obs, rust_obs[k + 1]), f"observations differ at step {k}"
        assert np.array_equal(reward, rust_rewards[k]), f"rewards differ at step {k}"
        assert np.array_equal(info["position_error_m"], rust_errors[k])
        assert np.array_equal(terminated, rust_terminated[k]) and np.array_equal(truncated, rust_truncated[k])
        ended += int((terminated | truncated).sum())
    assert ended > 0, "the trace covers episode ends and resets"


def test_set_reference_flies_the_given_path():
    env = flapper.FlightVectorEnv(2, stage=3, seed=0)
    names = [name for name, _ in flapper.reference_names()]
    assert {"cruise", "longitudinal", "lateral", "loop", "aerobatic"} <= set(names)
    env.set_reference("loop", env_index=1)
    loop = env.reference_points(1)
    assert loop.shape[1] == 3 and np.allclose(loop[0], flapper.named_reference_start_m())
    assert np.ptp(loop[:, 2]) > 3, "a loop climbs and comes back"
    line = np.zeros((200, 3))
    line[:, 0] = np.arange(200) * 0.02 * 4.0
    line[:, 2] = 12.0
    env.set_reference(line)
    assert np.array_equal(env.reference_points(0), line) and np.array_equal(env.reference_points(1), line)
