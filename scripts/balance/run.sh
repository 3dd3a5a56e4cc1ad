#!/usr/bin/env bash
# One traced run of ten-spheres (scripts/balance/trace.patch must be applied to the
# binaries in BIN): MODE = local2 (crash run --threads 2) or cluster (master + 2
# workers x 1 thread, the bench's command lines). Trace to OUT/trace.csv.
# Usage: run.sh BIN MODE OUT [END]
set -euo pipefail
BIN=$1 MODE=$2 OUT=$3 END=${4:-2e-3}
SCENE=${SCENE:-scenes/ten-spheres-three-plates.toml}
rm -rf "$OUT"; mkdir -p "$OUT"
export RUST_LOG=warn CRASH_STEP_TRACE=$OUT/trace.csv
unset CRASH_SECRET
if [ "$MODE" = local2 ]; then
  "$BIN/crash" run "$SCENE" --threads 2 --end-time "$END" --output-interval "$END" \
    --out "$OUT/run" --quiet --no-pictures --allow-warnings 2>/dev/null
else
  "$BIN/crash-master" "$SCENE" --listen 127.0.0.1:0 --split off --workers 2 \
    --out "$OUT/run" --end-time "$END" --output-interval "$END" 2>"$OUT/master.log" &
  M=$!
  for _ in $(seq 100); do
    ADDR=$(sed -n 's/^crash-master: listening on //p' "$OUT/master.log" | head -1)
    [ -n "$ADDR" ] && break; sleep 0.1
  done
  "$BIN/crash-worker" --master "http://$ADDR" --threads 1 2>/dev/null & W1=$!
  "$BIN/crash-worker" --master "http://$ADDR" --threads 1 2>/dev/null & W2=$!
  wait $M; wait $W1 $W2 || true
fi
python3 -c "import json,sys; s=json.load(open('$OUT/run/summary.json')); print('$MODE', s['wall_time_s'], s['final_state_hash'], s.get('compute_ns_per_worker'))"
