#!/usr/bin/env bash
# Trains the curriculum's stage 1 again with the shipped seed and compares its training.csv with the shipped
# one (policies/final/stage1/training.csv) row for row, timing columns apart. Training is reproducible on the
# same CPU model with the same thread count, not across CPU models (policies/final/README.md: gemm's kernels
# and block sizes follow the CPU); about 2-3 minutes on 2 cores.
#   scripts/reproduce-stage1.sh [SHIPPED_DIR]   (default policies/final)
set -euo pipefail
shipped=${1:-policies/final}
seed=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['seed'])" "$shipped/summary.json")
out=$(mktemp -d)/curriculum
trap 'rm -rf "$(dirname "$out")"' EXIT
cargo run --release --quiet -p flapper-cli -- curriculum --out "$out" --seed "$seed" --until-stage 1
python3 - "$shipped/stage1/training.csv" "$out/stage1/training.csv" <<'PY'
import csv, json, os, sys
timing = {"wall_time_s", "steps_per_s", "env_time_s", "inference_time_s", "update_time_s"}
shipped, again = (list(csv.DictReader(open(path))) for path in sys.argv[1:3])


def machines():
    # Each run records the CPU that trained it (`cpu` in selected.json, written by the binary).
    here, shipped_at = (json.load(open(os.path.join(os.path.dirname(path), "selected.json"))).get("cpu", "not recorded")
                        for path in (sys.argv[2], sys.argv[1]))
    return (f"this CPU: {here}; the shipped stage 1 was trained on {shipped_at}; training reproduces on the CPU "
            "model it ran on, policies/final/README.md")


for row, (a, b) in enumerate(zip(shipped, again), start=1):
    differing = [k for k in a if k not in timing and a[k] != b.get(k)]
    if differing:
        sys.exit(f"reproduce-stage1: row {row} differs in {', '.join(differing)} ({machines()})")
if len(shipped) != len(again):
    sys.exit(f"reproduce-stage1: {len(again)} rows against the shipped {len(shipped)} ({machines()})")
print(f"reproduce-stage1: {len(again)} rows identical to {sys.argv[1]} (timing columns apart)")
PY
