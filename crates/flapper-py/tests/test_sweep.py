"""flapper.sweep: a tiny sweep (two seeds of a few training iterations) on a local Ray started and
stopped by the sweep, then run again: finished trials are skipped, nothing of Ray is left running."""

import csv
import subprocess
import tomllib

import pytest

from conftest import ROOT, cargo_run

pytest.importorskip("ray", reason="the sweep extra: pip install './crates/flapper-py[sweep]'")
from flapper.sweep import SweepError, load_sweep, run_sweep, trial_config  # noqa: E402

TINY_TRAIN = """[runner]
envs = 4
iterations = 3
checkpoint_every = 1
[ppo]
steps_per_env = 8
minibatches = 2
actor_hidden = [16]
critic_hidden = [16]
[task]
stage = 1
"""


def ray_processes():
    found = subprocess.run(["pgrep", "-f", "raylet|gcs_server"], capture_output=True, text=True).stdout.split()
    return found


def test_a_tiny_sweep_runs_reports_resumes_and_leaves_nothing_behind(tmp_path):
    cargo_run("flapper-cli", [], ["--version"])  # builds target/release/flapper
    (tmp_path / "tiny.toml").write_text(TINY_TRAIN)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('command = "train"\nconfig = "tiny.toml"\nseeds = [1, 2]\ncpus_per_trial = 1\n'
                     '[evaluation]\nreferences = ["cruise"]\nepisodes = 2\nseed = 11\n')
    out = tmp_path / "out"
    flapper = str(ROOT / "target" / "release" / "flapper")
    trials = run_sweep(sweep, out, flapper=flapper, poll_s=0.5, num_cpus=2)
    assert not ray_processes(), "the local Ray is stopped"
    assert [t["seed"] for t in trials] == [1, 2]
    rows = list(csv.DictReader(open(out / "results.csv")))
    assert list(rows[0]) == ["seed", "total_env_steps", "total_wall_time_s", "cruise_completed", "cruise_rms_m"]
    assert [int(r["seed"]) for r in rows] == [1, 2]
    assert all(int(r["total_env_steps"]) == 3 * 4 * 8 for r in rows)
    assert all(0 <= int(r["cruise_completed"]) <= 2 and float(r["cruise_rms_m"]) > 0 for r in rows)
    assert (out / "results.png").stat().st_size > 1000
    # Each trial trained its own seed (the run folders differ) and reported its progress to Ray Tune.
    seeds = [open(out / f"trials/base-seed{s}/run/config.toml").read() for s in (1, 2)]
    assert "seed = 1" in seeds[0] and "seed = 2" in seeds[1]
    reported = list((out / "ray").rglob("result.json"))
    assert len(reported) == 2 and all('"iteration": 3' in p.read_text() for p in reported)

    # Again: both trials finished, so nothing trains and Ray is not even started.
    before = (out / "trials/base-seed1/run/training.csv").read_text()
    run_sweep(sweep, out, flapper=flapper, poll_s=0.5, num_cpus=2)
    assert (out / "trials/base-seed1/run/training.csv").read_text() == before
    assert list(csv.DictReader(open(out / "results.csv"))) == rows


def test_bad_sweep_files_are_refused_naming_the_problem(tmp_path):
    (tmp_path / "tiny.toml").write_text(TINY_TRAIN)
    for text, needle in [
        ('config = "tiny.toml"\nseeds = [1, 1]\n', "distinct"),
        ('config = "missing.toml"\nseeds = [1]\n', "does not exist"),
        ('config = "tiny.toml"\nseeds = [1]\ncommand = "dance"\n', "command"),
        ('config = "tiny.toml"\nseeds = [1]\nseeed = 2\n', "seeed"),
        ('config = "tiny.toml"\nseeds = [1]\n[[variants]]\nname = "a b"\n', "variant"),
    ]:
        path = tmp_path / "bad.toml"
        path.write_text(text)
        with pytest.raises(SweepError, match=needle):
            load_sweep(path)


def test_a_trial_of_a_config_that_extends_another_still_finds_its_base(tmp_path):
    (tmp_path / "experiments").mkdir()
    (tmp_path / "experiments" / "x.toml").write_text('extends = "../base.toml"\nseed = 4\n')
    (tmp_path / "base.toml").write_text("seed = 3\n")
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('config = "experiments/x.toml"\nseeds = [1]\n')
    text = trial_config(load_sweep(sweep), {"name": "base"})
    written = tomllib.loads(text)
    assert written["extends"] == str(tmp_path.resolve() / "base.toml") and written["seed"] == 4, text
