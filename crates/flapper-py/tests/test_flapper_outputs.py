"""scripts/flapper_outputs.py reads what flapper's measuring commands write: through it, seed-table's
identification and frontier columns for the shipped controller come out as policies/final/seeds.csv
recorded them for seed 1 (flapper's evaluation is bit for bit the same on every CPU), and a policy's modes
name the longitudinal reference's four segments."""

import csv
import importlib.util
import subprocess

import flapper_outputs
import pytest

from conftest import ROOT

spec = importlib.util.spec_from_file_location("seed_table", ROOT / "scripts" / "seed-table.py")
seed_table = importlib.util.module_from_spec(spec)
spec.loader.exec_module(seed_table)

FINAL = ROOT / "policies" / "final" / "policy.safetensors"


@pytest.fixture(scope="module")
def flapper():
    """seed-table's runner ($FLAPPER, else the release binary, built here if it is not yet)."""
    subprocess.run(["cargo", "build", "--release", "--quiet", "-p", "flapper-cli"], cwd=ROOT, check=True)
    return seed_table.Flapper(None)


@pytest.fixture(scope="module")
def recorded():
    """policies/final/seeds.csv's row for seed 1, the shipped controller."""
    with open(ROOT / "policies" / "final" / "seeds.csv", newline="") as f:
        return next(row for row in csv.DictReader(f) if row["seed"] == "1")


def test_seed_table_identification_reproduces_the_recorded_fits(flapper, recorded, tmp_path):
    row = seed_table.sysid(flapper, FINAL, tmp_path)
    for axis in "xyz":
        key = f"sysid_fit_{axis}_percent"
        assert row[key] == float(recorded[key]), key
    assert str(row["sysid_bar_met"]) == recorded["sysid_bar_met"]


def test_seed_table_frontier_reproduces_the_recorded_efficiency(flapper, recorded, tmp_path):
    row = seed_table.frontier(flapper, FINAL, tmp_path)
    for key in ["energy_ratio", "glide_fraction", "cruise_flap_hz", "level3_rms_m"]:
        assert row[key] == pytest.approx(float(recorded[key]), abs=1e-9), key
    assert row["level3_completed"] == int(recorded["level3_completed"])
    # The policy's point is the first row; the scripted gait's, the yardstick, comes after it.
    point = flapper_outputs.frontier_point(tmp_path / "frontier")
    assert point["label"] != "scripted gait"
    assert float(point["energy_ratio"]) == pytest.approx(
        float(point["longitudinal_j_per_m"]) / float(point["scripted_j_per_m"]), abs=2e-3)


def test_modes_segments_are_the_longitudinal_references_four(flapper, tmp_path):
    flapper(["modes", "--policy", str(FINAL)], tmp_path)
    segments = flapper_outputs.modes_segments(tmp_path)
    assert set(segments) == {"cruise", "climb", "glide", "dive"}
    assert all(0.0 <= s["glide_fraction"] <= 1.0 for s in segments.values())
    assert 4.0 <= segments["cruise"]["flap_fundamental_hz"] <= 8.0, "the shipped controller flaps in cruise"


def test_a_missing_output_is_an_error_naming_the_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="sysid.json"):
        flapper_outputs.identified_fits(tmp_path)
