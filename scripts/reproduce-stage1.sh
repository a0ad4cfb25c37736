#!/usr/bin/env bash
# Trains the curriculum's stage 1 again with a recorded run's seed and compares its training.csv with the
# recorded one row for row, timing columns apart. Training computes the same bits on every x86-64 CPU with
# AVX2 and FMA and on any thread count (docs/training.md, "Training that reproduces on any CPU and thread
# count"); about 2-3 minutes on 2 cores.
#   scripts/reproduce-stage1.sh [RECORDED_DIR]
# FLAPPER_BIN=PATH uses a binary built elsewhere instead of building one (a machine without a Rust toolchain).
# RECORDED_DIR holds summary.json and stage1/training.csv; the default is the shipped final controller's run
# (policies/final, seed 1, the fixed arithmetic). docs/runs/seed3/ is another such record; the previous final
# controller (policies/history/previous-final) was trained with the arithmetic before it (gemm) and reproduces
# only on the CPU model that trained it.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
recorded=${1:-$root/policies/final}
for file in summary.json stage1/training.csv; do
    if [[ ! -f "$recorded/$file" ]]; then
        echo "error: $recorded/$file not found (RECORDED_DIR must hold a curriculum run's summary.json and stage1/)" >&2
        exit 1
    fi
done
seed=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['seed'])" "$recorded/summary.json")
out=$(mktemp -d)/curriculum
trap 'rm -rf "$(dirname "$out")"' EXIT
cd "$root"
if [[ -n "${FLAPPER_BIN:-}" ]]; then
    "$FLAPPER_BIN" curriculum --out "$out" --seed "$seed" --until-stage 1
else
    cargo run --release --quiet -p flapper-cli -- curriculum --out "$out" --seed "$seed" --until-stage 1
fi
python3 - "$recorded/stage1/training.csv" "$out/stage1/training.csv" <<'PY'
import csv, json, os, sys
timing = {"wall_time_s", "steps_per_s", "env_time_s", "inference_time_s", "update_time_s"}
recorded, again = (list(csv.DictReader(open(path))) for path in sys.argv[1:3])


def machines():
    # Each run records the CPU that trained it (`cpu` in selected.json, written by the binary).
    here, recorded_at = (json.load(open(os.path.join(os.path.dirname(path), "selected.json"))).get("cpu", "not recorded")
                         for path in (sys.argv[2], sys.argv[1]))
    return f"this CPU: {here}; the recorded stage 1 was trained on {recorded_at}"


for row, (a, b) in enumerate(zip(recorded, again), start=1):
    differing = [k for k in a if k not in timing and a[k] != b.get(k)]
    if differing:
        sys.exit(f"reproduce-stage1: row {row} differs in {', '.join(differing)} ({machines()})")
if len(recorded) != len(again):
    sys.exit(f"reproduce-stage1: {len(again)} rows against the recorded {len(recorded)} ({machines()})")
print(f"reproduce-stage1: {len(again)} rows identical to {sys.argv[1]} (timing columns apart; {machines()})")
PY
