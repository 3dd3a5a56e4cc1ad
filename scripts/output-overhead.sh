#!/usr/bin/env bash
# What writing frames costs the step loop (issue 17, point 5): the showcase run with a
# frame every N steps against frames only at the start and the end, interleaved
# repetitions, medians of summary.json's ns per element-cycle ("total" and "output").
# Usage: scripts/output-overhead.sh [END_TIME [EVERY_STEPS [REPS [PRECISION]]]]
# (default 5e-3 s, every 50 steps, 3 repetitions, f64). Needs target/release/crash.
set -euo pipefail
cd "$(dirname "$0")/.."
END=${1:-5e-3}; EVERY=${2:-50}; REPS=${3:-3}; PREC=${4:-f64}
SCENE=scenes/sphere-on-plate.toml
CRASH=${CRASH:-target/release/crash}   # another build to compare: CRASH=/path/to/crash
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
# the first step's dt, from crash check (the step hardly changes in this run)
DT=$("$CRASH" check "$SCENE" | sed -n 's/^time step estimate \([0-9.e+-]*\) s.*/\1/p')
INTERVAL=$(python3 -c "print($DT * $EVERY)")
SCENE_P="$OUT/scene.toml"
{ cat "$SCENE"; printf '\n[outputs]\nprecision = "%s"\n' "$PREC"; } > "$SCENE_P"
run() { # $1 label, $2 interval
  rm -rf "$OUT/run"
  "$CRASH" run "$SCENE_P" --end-time "$END" --output-interval "$2" --threads 1 \
    --no-pictures --quiet --out "$OUT/run" >/dev/null 2>&1
  python3 - "$OUT/run/summary.json" "$1" <<'PY' >> "$OUT/rows"
import json, sys, pathlib
d = json.load(open(sys.argv[1])); n = d["ns_per_element_cycle"]
frames = len(list(pathlib.Path(sys.argv[1]).parent.glob("frames/*.vtu")))
size = sum(p.stat().st_size for p in pathlib.Path(sys.argv[1]).parent.glob("frames/*.vtu"))
print(sys.argv[2], n["total"], n.get("output", 0.0), frames, size, d["final_state_hash"])
PY
}
for r in $(seq "$REPS"); do
  run off "$END"
  run on "$INTERVAL"
done
python3 - "$OUT/rows" "$EVERY" "$PREC" <<'PY'
import sys, statistics as st
rows = [l.split() for l in open(sys.argv[1])]
def med(label, k): return st.median(float(r[k]) for r in rows if r[0] == label)
off, on = med("off", 1), med("on", 1)
frames = int(med("on", 3)); size = med("on", 4)
print(f"frames only at start and end: {off:.1f} ns per element-cycle (median)")
print(f"a frame every {sys.argv[2]} steps ({frames} frames, {sys.argv[3]}, {size/frames/1e6:.2f} MB each): "
      f"{on:.1f} ns per element-cycle, of which output {med('on', 2):.2f} (median)")
print(f"cost of the frames: {100 * (on / off - 1):+.1f} %")
hashes = {r[5] for r in rows}
print("same final state hash" if len(hashes) == 1 else f"hashes differ: {hashes}")
PY
