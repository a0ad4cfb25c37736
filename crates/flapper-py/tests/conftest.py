"""Shared helpers: the repository root and the Rust programs the tests compare against."""

import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]
# The scripts' shared module (scripts/flapper_outputs.py), importable as it is when a script runs from there.
sys.path.insert(0, str(ROOT / "scripts"))


def cargo_run(package, target_args, args):
    """Runs a release build of a workspace program (built on first use) and returns its stdout."""
    command = ["cargo", "run", "--release", "--quiet", "-p", package, *target_args, "--", *map(str, args)]
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        raise AssertionError(f"{' '.join(command)} failed:\n{done.stderr}")
    return done.stdout


@pytest.fixture(scope="session")
def root():
    return ROOT
