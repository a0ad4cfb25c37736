#!/usr/bin/env bash
# How training scales with cores: `flapper bench` pinned to the first N cores (taskset) for N = 1, 2, 4, ...
# up to every core, one table row each: environments alone, the PPO update, training end to end.
#   scripts/bench-scaling.sh [MAX_THREADS]   (default: every core; builds the release binary first)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
cores=$(nproc)
max=${1:-$cores}
if ! [[ "$max" =~ ^[1-9][0-9]*$ ]] || (( max > cores )); then
    echo "error: MAX_THREADS must be 1 to $cores (the cores here), got '$max'" >&2
    exit 1
fi
cargo build --release --quiet -p flapper-cli
flapper=target/release/flapper
counts=()
for ((n = 1; n < max; n *= 2)); do counts+=("$n"); done
counts+=("$max")
echo "CPU: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'); vector path: ${FLAPPER_SIMD:-widest}"
printf '%8s %22s %22s %24s %12s\n' threads "environments (steps/s)" "PPO update (samples/s)" "training (steps/s)" "update share"
for n in "${counts[@]}"; do
    out=$(taskset -c "0-$((n - 1))" "$flapper" bench --threads "$n" --blocks 5 --steps 2000 --train-iterations 6)
    env=$(awk '/environment steps\/s  median/ && !t {print $4; t=1}' <<<"$out")
    update=$(awk '/forward \+ backward \+ Adam/ {print $7}' <<<"$out")
    train=$(awk '/PPO training end to end/ {f=1} f && /environment steps\/s/ {print $4; exit}' <<<"$out")
    share=$(awk '/time split/ {print $NF}' <<<"$out")
    printf '%8s %22s %22s %24s %12s\n' "$n" "$env" "$update" "$train" "$share"
done
