#!/usr/bin/env python3
"""The seed study of the one-command curriculum: judge each finished `flapper curriculum` run folder
against the final controller's bars and write the table `policies/final/seeds.csv` asks for.

    scripts/seed-table.py --out seeds.csv RUN_DIR [RUN_DIR ...] [--robustness] [--sysid] [--frontier]
    scripts/seed-table.py --out light.csv --model examples/robots/light.xml RUN_DIR   (another robot's run)

For every folder (its `summary.json` and `policy.safetensors`): the eight named references flown from 100
starts with seed 11 (`flapper eval --no-baseline`), and with --robustness the sweeps behind the robustness
bars (`flapper robustness --sweeps fluid,table3 --ranges 0.3 --episodes 100 --seed 1` on lateral and
longitudinal), with --sysid the identified closed loop's validation fit (`flapper sysid`), with --frontier
the efficient-bird figures (`flapper frontier --episodes 100 --seed 11`: energy per metre on longitudinal over
the scripted gait's on the same starts, the glide fraction of its glide segment, the cruise flap frequency,
level 3 m/s completed and RMS). Columns:
seed, total_env_steps, total_wall_time_s, stages_trained (the stages that handed over a controller),
optional_stage_missed (the optional last stage whose gate the run missed, ending it with the stage before's
controller; empty if none), <reference>_completed (of 100), <reference>_rms_m, then
nominal_bars_met and the optional robustness and sysid columns. A run that stopped at a missed gate (a
summary, no policy) is a row of its own with empty flight columns and no bar met (its steps and time include
the stage that missed): a seed that fails counts. With --model every flight flies that robot (the MJCF the
runs were trained on, `flapper curriculum --model`) and a first column `robot` names it. Prints the table and how many seeds meet
every nominal bar. The flapper binary: $FLAPPER, else target/release/flapper.
"""

import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from flapper_outputs import EFFICIENCY_BARS, frontier_bars_met, frontier_point, identified_fits

REFERENCES = ["cruise", "longitudinal", "lateral", "sharp-turn", "loop", "immelmann", "roll-off-the-bottom", "aerobatic"]
# The one-command curriculum issue's nominal bars: (completed of 100 at least, mean RMS error at most, m).
NOMINAL_BARS = {
    "cruise": (95, 0.3),
    "longitudinal": (95, 0.3),
    "lateral": (95, 0.35),
    **{name: (95, None) for name in ["sharp-turn", "loop", "immelmann", "roll-off-the-bottom", "aerobatic"]},
}
# Its robustness bars, in percent: Table III at once on lateral; all five fluid coefficients x[0.7, 1.3].
ROBUSTNESS_BARS = {"lateral_table3": 90, "lateral_fluid_all_0.3": 95, "longitudinal_fluid_all_0.3": 95}
SYSID_BAR_PERCENT = 80.0


class Flapper:
    """Runs the flapper binary ($FLAPPER, else target/release/flapper) on one robot: `model`, the MJCF the
    runs were trained on, or None for the shipped models/flapper.xml."""

    def __init__(self, model):
        default = Path(__file__).resolve().parent.parent / "target/release/flapper"
        self.binary = os.environ.get("FLAPPER", str(default))
        self.model_args = [] if model is None else ["--model", str(model)]

    def __call__(self, args, scratch):
        done = subprocess.run([self.binary, *args, *self.model_args, "--out", str(scratch)],
                              capture_output=True, text=True)
        if done.returncode != 0:
            sys.exit(f"seed-table: flapper {' '.join(args)} failed: {done.stderr.strip().splitlines()[-1:]}")


def spent_in_stage(stage_dir):
    """Environment steps and seconds (training and validation) a stage spent before it stopped: what a run
    that missed the stage's gate spent there, which the summary.json of a run recorded before `stopped` was
    kept does not count (a newer summary counts it in its totals)."""
    training = stage_dir / "training.csv"
    if not training.is_file():
        return None
    rows = list(csv.DictReader(open(training)))
    if not rows:
        return None
    # The training clock runs through the validations between iterations; only the last one comes after it.
    last = int(rows[-1]["iteration"])
    validations = stage_dir / "selection.csv"
    after = [r for r in csv.DictReader(open(validations)) if int(r["iteration"]) >= last] if validations.is_file() else []
    return int(rows[-1]["env_steps"]), float(rows[-1]["wall_time_s"]) + sum(float(r["validation_s"]) for r in after)


def nominal(flapper, policy, scratch):
    row = {}
    for name in REFERENCES:
        out = scratch / f"eval-{name}"
        flapper(["eval", "--policy", str(policy), "--reference", name, "--episodes", "100", "--seed", "11",
                 "--no-baseline"], out)
        metrics = {r["metric"]: r["policy"] for r in csv.DictReader(open(out / "summary.csv"))}
        row[f"{name}_completed"] = int(metrics["completed"].split("/")[0])
        row[f"{name}_rms_m"] = float(metrics["RMS position error (m), mean"])
    row["nominal_bars_met"] = all(
        row[f"{name}_completed"] >= completed and (rms is None or row[f"{name}_rms_m"] <= rms)
        for name, (completed, rms) in NOMINAL_BARS.items()
    )
    return row


def robustness(flapper, policy, scratch):
    row = {}
    for name in ["lateral", "longitudinal"]:
        out = scratch / f"robustness-{name}"
        flapper(["robustness", "--policy", str(policy), "--reference", name, "--episodes", "100", "--seed", "1",
                 "--sweeps", "fluid,table3", "--ranges", "0.3"], out)
        result = json.load(open(out / "robustness.json"))
        row[f"{name}_table3"] = result["table_iii"]["successes"]
        row[f"{name}_fluid_all_0.3"] = next(
            f["successes"] for f in result["fluid"] if f["coefficient"] == "all" and abs(f["range"] - 0.3) < 1e-9
        )
    row["robustness_bars_met"] = all(row[key] >= bar for key, bar in ROBUSTNESS_BARS.items())
    return row


def sysid(flapper, policy, scratch):
    out = scratch / "sysid"
    flapper(["sysid", "--policy", str(policy)], out)
    row = {f"sysid_fit_{axis}_percent": round(fit, 1) for axis, fit in identified_fits(out).items()}
    row["sysid_bar_met"] = all(row[f"sysid_fit_{axis}_percent"] >= SYSID_BAR_PERCENT for axis in "xyz")
    return row


# The efficient-bird issue's figures flapper frontier measures (its bars: flapper_outputs.frontier_bars_met).
FRONTIER_COLUMNS = ["energy_ratio", "glide_fraction", "cruise_flap_hz", "level3_completed", "level3_rms_m"]


def frontier(flapper, policy, scratch):
    out = scratch / "frontier"
    flapper(["frontier", "--policy", str(policy), "--episodes", "100", "--seed", "11"], out)
    measured = frontier_point(out)
    row = {key: (float(measured[key]) if measured[key] not in ("", "NaN") else None) for key in FRONTIER_COLUMNS}
    row["level3_completed"] = None if row["level3_completed"] is None else int(row["level3_completed"])
    for key in ["energy_ratio", "glide_fraction", "cruise_flap_hz", "level3_rms_m"]:
        if row[key] is not None:
            row[key] = round(row[key], 3)
    met = frontier_bars_met(row["energy_ratio"], row["glide_fraction"], row["cruise_flap_hz"])
    row["efficiency_bars_met"] = EFFICIENCY_BARS <= met
    return row


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="finished `flapper curriculum` folders")
    parser.add_argument("--out", type=Path, required=True, help="the table to write (CSV; must not exist)")
    parser.add_argument("--robustness", action="store_true", help="also the robustness bars (~3 min a seed)")
    parser.add_argument("--sysid", action="store_true", help="also the identification bar (~1 min a seed)")
    parser.add_argument("--frontier", action="store_true",
                        help="also energy ratio, glide fraction, cruise flap Hz and level 3 m/s (~1 min a seed)")
    parser.add_argument("--model", type=Path,
                        help="the robot (MJCF) the runs were trained on; default the shipped models/flapper.xml")
    args = parser.parse_args()
    if args.model is not None:
        if not args.model.is_file():
            sys.exit(f"seed-table: --model '{args.model}' is not a file")
    if args.out.exists():
        sys.exit(f"seed-table: '{args.out}' exists; choose another --out (nothing was overwritten)")
    for run in args.runs:
        if not (run / "summary.json").is_file():
            sys.exit(f"seed-table: '{run}' has no summary.json: not a `flapper curriculum` run")
    flapper = Flapper(args.model)
    rows = []
    for run in args.runs:
        summary = json.load(open(run / "summary.json"))
        row = {
            **({"robot": args.model.name} if args.model is not None else {}),
            "seed": summary["seed"],
            "total_env_steps": summary["total_env_steps"],
            "total_wall_time_s": round(summary["total_wall_time_s"], 1),
            "stages_trained": len(summary["stages"]),
            "optional_stage_missed": summary["optional_stage_missed"]["stage"]
            if "optional_stage_missed" in summary else "",
        }
        if not (run / "policy.safetensors").is_file():
            done = len(summary["stages"])
            missed = None if "stopped" in summary else spent_in_stage(run / f"stage{done + 1}")
            if missed:
                row["total_env_steps"] += missed[0]
                row["total_wall_time_s"] = round(row["total_wall_time_s"] + missed[1], 1)
            print(f"seed {row['seed']}: no controller ('{run}' finished {done} stages"
                  + (f" and stopped in stage {done + 1}, whose steps and time are counted"
                     if missed or "stopped" in summary else "")
                  + ")", flush=True)
            rows.append({**row, "nominal_bars_met": False})
            continue
        with tempfile.TemporaryDirectory() as scratch:
            policy = run / "policy.safetensors"
            row.update(nominal(flapper, policy, Path(scratch)))
            if args.robustness:
                row.update(robustness(flapper, policy, Path(scratch)))
            if args.sysid:
                row.update(sysid(flapper, policy, Path(scratch)))
            if args.frontier:
                row.update(frontier(flapper, policy, Path(scratch)))
        print(", ".join(f"{k} {v}" for k, v in row.items()), flush=True)
        rows.append(row)
    columns = max((list(row.keys()) for row in rows), key=len)
    with open(args.out, "w", newline="") as file:
        writer = csv.DictWriter(file, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    met = sum(row["nominal_bars_met"] for row in rows)
    print(f"{met} of {len(rows)} seeds meet every nominal bar; wrote {args.out}")


if __name__ == "__main__":
    main()
