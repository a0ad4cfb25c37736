"""scripts/example-paths.py writes the example paths in examples/: the committed files are its output byte for
byte, each path starts at (0, 0, 10) m heading along x, is sampled at 10 Hz and flown at 4 m/s along the
ground, and the helix climbs while the spiral sinks; a folder that does not exist is refused."""

import csv
import importlib.util
import math
import subprocess
import sys

from conftest import ROOT

SCRIPT = ROOT / "scripts" / "example-paths.py"
spec = importlib.util.spec_from_file_location("example_paths", SCRIPT)
example_paths = importlib.util.module_from_spec(spec)
spec.loader.exec_module(example_paths)


def read(path):
    with open(path) as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def test_the_committed_examples_are_the_script_s_output(tmp_path):
    subprocess.run([sys.executable, str(SCRIPT), "--out", str(tmp_path)], check=True, capture_output=True)
    for name in example_paths.PATHS:
        written = (tmp_path / f"{name}.csv").read_bytes()
        assert written == (ROOT / "examples" / f"{name}.csv").read_bytes(), name


def test_each_path_starts_level_at_ten_metres_and_flies_four_metres_a_second(tmp_path):
    subprocess.run([sys.executable, str(SCRIPT), "--out", str(tmp_path)], check=True, capture_output=True)
    for name in example_paths.PATHS:
        rows = read(tmp_path / f"{name}.csv")
        assert (rows[0]["x_m"], rows[0]["y_m"], rows[0]["z_m"]) == (0.0, 0.0, 10.0), name
        assert rows[1]["x_m"] > 0.39 and abs(rows[1]["y_m"]) < 0.05, f"{name}: heads along x"
        for a, b in zip(rows, rows[1:]):
            assert math.isclose(b["time_s"] - a["time_s"], 0.1, abs_tol=1e-9), name
            ground = math.hypot(b["x_m"] - a["x_m"], b["y_m"] - a["y_m"]) / 0.1
            assert 3.9 < ground < 4.01, f"{name} at {a['time_s']} s: {ground} m/s"
    helix, spiral = read(tmp_path / "helix-climb.csv"), read(tmp_path / "spiral-descent.csv")
    assert math.isclose(helix[-1]["z_m"] - helix[0]["z_m"], 0.4 * 20, abs_tol=1e-6)
    assert math.isclose(spiral[-1]["z_m"] - spiral[0]["z_m"], -0.5 * 20, abs_tol=1e-6)
    assert spiral[10]["y_m"] < 0 < helix[10]["y_m"], "the spiral turns right, the helix left"
    eight = read(tmp_path / "figure-eight.csv")
    assert min(r["y_m"] for r in eight) < -13 and max(r["y_m"] for r in eight) > 13, "both circles flown"


def test_a_folder_that_does_not_exist_is_refused(tmp_path):
    run = subprocess.run([sys.executable, str(SCRIPT), "--out", str(tmp_path / "nowhere")], capture_output=True, text=True)
    assert run.returncode != 0 and "no such folder" in run.stderr and run.stdout == ""
