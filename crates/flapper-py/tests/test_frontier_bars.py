"""scripts/frontier-bars.py judges frontier.csv rows against the efficient-bird bars frontier measures: each bar
at its boundary, level 3 m/s only where the controller completes it in 95% of its episodes, and a file that is
not a frontier.csv refused with one line naming it."""

import importlib.util
import subprocess
import sys

from conftest import ROOT

SCRIPT = ROOT / "scripts" / "frontier-bars.py"
spec = importlib.util.spec_from_file_location("frontier_bars", SCRIPT)
frontier_bars = importlib.util.module_from_spec(spec)
spec.loader.exec_module(frontier_bars)

HEADER = "label,energy_ratio,glide_fraction,cruise_flap_hz,level3_completed,level3_episodes,level3_rms_m,source\n"


def test_each_bar_is_met_at_its_boundary_and_not_past_it():
    row = {"label": "a", "energy_ratio": "1.5", "glide_fraction": "0.5", "cruise_flap_hz": "6.0",
           "level3_completed": "95", "level3_episodes": "100", "level3_rms_m": "0.5"}
    assert frontier_bars.judge(row)["met"] == {"energy", "glide", "flap", "level3"}
    past = {**row, "energy_ratio": "1.51", "glide_fraction": "0.49", "cruise_flap_hz": "6.01", "level3_rms_m": "0.51"}
    assert frontier_bars.judge(past)["met"] == set()
    # Slow flight counts only where it is flown: 94 of 100 at 0.2 m does not meet bar 5.
    assert "level3" not in frontier_bars.judge({**row, "level3_completed": "94"})["met"]
    assert frontier_bars.judge({**row, "cruise_flap_hz": ""})["met"] == {"energy", "glide", "level3"}


def test_the_table_counts_rows_and_names_the_slowest_flyer_of_each_set(tmp_path):
    points = tmp_path / "frontier.csv"
    points.write_text(HEADER
                      + "glider,1.2,0.8,5.0,100,100,0.8,x\n"
                      + "slow,7.0,0.0,,100,100,0.2,x\n"
                      + "cheap,1.4,0.0,5.5,100,100,0.6,x\n")
    rows = frontier_bars.read_rows([points])
    lines = frontier_bars.table(rows).splitlines()
    by_set = {line.split(" | ")[0].strip("| "): line for line in lines[2:]}
    assert "| 2 of 3 | 0.600 | cheap |" in by_set["1"]
    assert "| 1 of 3 | 0.800 | glider |" in by_set["1+2+3"]
    assert "| 1 of 3 | 0.200 | slow |" in by_set["5"]
    assert "| 0 of 3 | - |" in by_set["1+2+3+5"]


def test_a_file_that_is_not_a_frontier_csv_is_refused_with_one_line(tmp_path):
    other = tmp_path / "other.csv"
    other.write_text("a,b\n1,2\n")
    done = subprocess.run([sys.executable, str(SCRIPT), str(other)], capture_output=True, text=True)
    assert done.returncode == 1
    assert done.stderr.count("\n") == 1 and str(other) in done.stderr and "not a frontier.csv" in done.stderr
