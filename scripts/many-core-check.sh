#!/usr/bin/env bash
# What 2 cores cannot show, in one run on a many-core machine (the lent 16-core one), with a release binary
# built elsewhere (FLAPPER_BIN, default target/release/flapper; no Rust toolchain needed there):
#   1. scripts/bench-scaling.sh ROUNDS times (default 3) on the widest vector path and once on AVX2 (FLAPPER_SIMD=avx2);
#   2. the golden test's short training run (crates/flapper-cli/tests/reproducible_training.rs) on 1 thread and
#      on every core, its checkpoint hashed and compared with the committed GOLDEN_CHECKPOINT_HASH;
#   3. scripts/reproduce-stage1.sh against policies/final on the widest path and on AVX2, on every core.
#   scripts/many-core-check.sh [OUT_DIR]   (default: the current folder; one text file per part)
set -uo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
out=$(mkdir -p "${1:-.}" && cd "${1:-.}" && pwd)
cd "$root"
export FLAPPER_BIN=${FLAPPER_BIN:-$root/target/release/flapper}
if [[ ! -x "$FLAPPER_BIN" ]]; then
    echo "error: $FLAPPER_BIN is not an executable (build it with cargo build --release -p flapper-cli, or set FLAPPER_BIN)" >&2
    exit 1
fi
lscpu >"$out/lscpu.txt" 2>&1

for ((round = 1; round <= ${ROUNDS:-3}; round++)); do scripts/bench-scaling.sh; done 2>&1 | tee "$out/scaling.txt"
FLAPPER_SIMD=avx2 scripts/bench-scaling.sh 2>&1 | tee "$out/scaling-avx2.txt"

golden=$(grep -o 'GOLDEN_CHECKPOINT_HASH: u64 = 0x[0-9a-f_]*' crates/flapper-cli/tests/reproducible_training.rs | sed 's/.*0x//; s/_//g')
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for threads in 1 "$(nproc)"; do
    printf '[runner]\nenvs = 12\niterations = 2\ncheckpoint_every = 1\nseed = 5\nthreads = %s\n[ppo]\nsteps_per_env = 16\n[task.episode]\nmax_steps = 40\n' \
        "$threads" >"$work/golden-$threads.toml"
    "$FLAPPER_BIN" train --config "$work/golden-$threads.toml" --out "$work/golden-$threads" >/dev/null 2>&1
    python3 - "$work/golden-$threads/checkpoints/iter_000002.safetensors" "$golden" "$threads" <<'PY'
import struct, sys
data = open(sys.argv[1], "rb").read()
header = struct.unpack("<Q", data[:8])[0]
h = 0xCBF29CE484222325
for byte in data[8 + header:]:
    h = ((h ^ byte) * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
verdict = "equals" if h == int(sys.argv[2], 16) else "DIFFERS FROM"
print(f"golden run on {sys.argv[3]} thread(s): checkpoint hash {h:016x} {verdict} the committed {sys.argv[2]}")
PY
done 2>&1 | tee "$out/golden.txt"

{
    scripts/reproduce-stage1.sh 2>&1 | tail -1
    FLAPPER_SIMD=avx2 scripts/reproduce-stage1.sh 2>&1 | tail -1
} | tee "$out/reproduce-stage1.txt"
