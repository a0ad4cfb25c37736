#!/usr/bin/env bash
# How training scales with cores: `flapper bench` pinned to the first N cores (taskset) for N = 1, 2, 4, ...
# up to every core, one table row each: environments alone, the PPO update, training end to end.
#   scripts/bench-scaling.sh [MAX_THREADS]   (default: every core; builds the release binary first)
# FLAPPER_BIN=PATH uses a binary built elsewhere instead (a machine without a Rust toolchain); where
# `taskset` cannot pin (some sandboxes), each row runs unpinned on N threads and the header says so.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
cores=$(nproc)
max=${1:-$cores}
if ! [[ "$max" =~ ^[1-9][0-9]*$ ]] || (( max > cores )); then
    echo "error: MAX_THREADS must be 1 to $cores (the cores here), got '$max'" >&2
    exit 1
fi
if [[ -n "${FLAPPER_BIN:-}" ]]; then
    flapper=$FLAPPER_BIN
    [[ -x "$flapper" ]] || { echo "error: FLAPPER_BIN=$flapper is not an executable file" >&2; exit 1; }
else
    cargo build --release --quiet -p flapper-cli
    flapper=target/release/flapper
fi
if taskset -c 0 true 2>/dev/null; then pin=1 pinning="pinned to the first N cores"
else pin=0 pinning="unpinned (taskset cannot pin here)"; fi
counts=()
for ((n = 1; n < max; n *= 2)); do counts+=("$n"); done
counts+=("$max")
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'); vector path: ${FLAPPER_SIMD:-widest}; $pinning"
printf '%8s %22s %22s %24s %12s\n' threads "environments (steps/s)" "PPO update (samples/s)" "training (steps/s)" "update share"
for n in "${counts[@]}"; do
    prefix=()
    ((pin)) && prefix=(taskset -c "0-$((n - 1))")
    out=$("${prefix[@]}" "$flapper" bench --threads "$n" --blocks 5 --steps 2000 --train-iterations 6)
    env=$(awk '/environment steps\/s  median/ && !t {print $4; t=1}' <<<"$out")
    update=$(awk '/forward \+ backward \+ Adam/ {print $7}' <<<"$out")
    train=$(awk '/PPO training end to end/ {f=1} f && /environment steps\/s/ {print $4; exit}' <<<"$out")
    share=$(awk '/time split/ {print $NF}' <<<"$out")
    printf '%8s %22s %22s %24s %12s\n' "$n" "$env" "$update" "$train" "$share"
done
