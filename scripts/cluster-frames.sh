#!/usr/bin/env bash
# One run of crash-master --split auto with two crash-worker processes x 1 thread on
# loopback, frames every INTERVAL seconds of simulated time: prints the wall time and
# the run's ns per element-cycle (total, output stage, barrier) from summary.json, and
# the final state hash. BIN: a directory with crash-master and crash-worker (default
# target/release; an older build there gives the A/B of docs/performance.md).
# WORKER_ARGS: more crash-worker options (e.g. "--poll-us 0": workers that block at once).
# Usage: [WORKER_ARGS=...] scripts/cluster-frames.sh SCENE END_TIME INTERVAL [BIN [PORT]]
set -euo pipefail
cd "$(dirname "$0")/.."
scene=$1 end=$2 every=$3 bin=${4:-target/release} port=${5:-7490}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$bin/crash-master" "$scene" --listen "127.0.0.1:$port" --split auto --workers 2 \
  --out "$out/run" --end-time "$end" --output-interval "$every" 2>"$out/master.log" &
sleep 0.3
for _ in 1 2; do
  # shellcheck disable=SC2086
  "$bin/crash-worker" --master "http://127.0.0.1:$port" --threads 1 ${WORKER_ARGS:-} 2>/dev/null &
done
wait
barrier=$(grep -o 'barrier per step: median [0-9.]* us' "$out/master.log" | grep -o '[0-9.]* us' || true)
python3 - "$out/run/summary.json" "$bin" "$every" "$barrier" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
n = s["ns_per_element_cycle"]
print(f"{sys.argv[2]} frames every {sys.argv[3]} s: wall {s['wall_time_s']:.3f} s, "
      f"ns/element-cycle total {n['total']:.2f}, output {n['output']:.2f}, "
      f"barrier {n['barrier']:.2f} (median {sys.argv[4]} a step), hash {s['final_state_hash']}")
PY
