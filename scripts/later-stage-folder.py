#!/usr/bin/env python3
"""Make a curriculum folder that holds a committed run's first stages, so that `flapper curriculum` trains
only the stages after them, from the committed controller.

A committed run record (policies/final/, docs/runs/NAME/) keeps each stage's `selected.json` and
`selection.csv` and the last stage's controller, not the checkpoints. This script writes a new folder with
`curriculum.toml`, the first STAGES stages' records and `summary.json`, and the controller put where the
last kept stage's `selected.json` names its checkpoint. Then

    flapper curriculum --config C [--seed S] --out FOLDER

reads those stages as done (C must hold the same first stages) and trains the rest from that controller.
The later stages start from the controller's weights, normalizer and step size, but with fresh Adam moments
(a policy file holds none), so their bits differ from a run that trained every stage in one go: a tool for
experiments on a later stage (docs/experiments.md, "A dearer dive, and what takes seed 2's dive"), not for
reproducing one.

    scripts/later-stage-folder.py --record docs/runs/path-starts-seed2 --out /tmp/s2
    scripts/later-stage-folder.py --record policies/final \
        --summary policies/experiments/glide-one-command/summary.json --out /tmp/s1

--summary takes the stage records from another summary.json of the same run (glide-one-command's holds
seed 1's stage 5 as it ended without its extension, which the shipped record spent).
"""
import argparse
import json
import os
import shutil
import sys


def fail(message):
    print(f"later-stage-folder: {message}", file=sys.stderr)
    sys.exit(2)


def read_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except OSError as e:
        fail(f"cannot read {path}: {e.strerror}")
    except json.JSONDecodeError as e:
        fail(f"{path} is not JSON (line {e.lineno}): {e.msg}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--record", required=True, help="a committed run record: curriculum.toml, stageN/, policy.safetensors")
    parser.add_argument("--out", required=True, help="the new folder (must not exist)")
    parser.add_argument("--stages", type=int, default=5, help="how many of its first stages to keep (default 5)")
    parser.add_argument("--summary", help="take the stage records from this summary.json (default: RECORD/summary.json)")
    parser.add_argument("--policy", help="the controller the next stage starts from (default: RECORD/policy.safetensors)")
    args = parser.parse_args()

    record = args.record
    summary_path = args.summary or os.path.join(record, "summary.json")
    policy = args.policy or os.path.join(record, "policy.safetensors")
    for path in (os.path.join(record, "curriculum.toml"), policy):
        if not os.path.isfile(path):
            fail(f"{path} is missing: --record must name a run record with curriculum.toml and its controller")
    if os.path.exists(args.out):
        fail(f"{args.out} exists: give --out a new folder (nothing was written)")
    if args.stages < 1:
        fail(f"--stages {args.stages}: keep at least one stage")

    summary = read_json(summary_path)
    stages = summary.get("stages", [])[: args.stages]
    if len(stages) < args.stages:
        fail(f"{summary_path} records {len(stages)} stages, fewer than --stages {args.stages}")
    for number, stage in enumerate(stages, start=1):
        if stage.get("stage") != number or "checkpoint" not in stage:
            fail(f"{summary_path}: stage record {number} has no stage number {number} or no checkpoint")

    os.makedirs(args.out)
    shutil.copy(os.path.join(record, "curriculum.toml"), args.out)
    for stage in stages:
        here = os.path.join(args.out, f"stage{stage['stage']}")
        os.makedirs(here)
        selection = os.path.join(record, f"stage{stage['stage']}", "selection.csv")
        if os.path.isfile(selection):
            shutil.copy(selection, here)
        with open(os.path.join(here, "selected.json"), "w") as f:
            json.dump(stage, f, indent=2)
    checkpoint = os.path.join(args.out, stages[-1]["checkpoint"])
    os.makedirs(os.path.dirname(checkpoint), exist_ok=True)
    shutil.copy(policy, checkpoint)
    summary = {key: value for key, value in summary.items() if key not in ("optional_missed", "stopped")}
    summary["stages"] = stages
    summary["total_env_steps"] = sum(s["env_steps"] for s in stages)
    summary["total_wall_time_s"] = sum(s["wall_time_s"] for s in stages)
    with open(os.path.join(args.out, "summary.json"), "w") as f:
        json.dump(summary, f, indent=2)
    print(f"{args.out}: stages 1-{len(stages)} of {record}, stage {len(stages) + 1} starts from {policy}")


if __name__ == "__main__":
    main()
