#!/usr/bin/env bash
# One sitting of the single-node figures of docs/performance.md (issue 17), in the order
# they are quoted: the element kernels (criterion medians of the 100k-element plates,
# ns per element-cycle), the stages of the showcase and of the OpenRadioss models at 1
# and 2 threads, frames every 50 steps (f64, f32), and the showcase as `crash run
# --threads 2` runs it (two domains) beside two threads sharing the loops. Run it on an otherwise idle
# machine (figures taken while something else runs are 30-70 % off); it prints the
# load before and after. About 14 minutes on 2 cores.
# Usage: scripts/sitting.sh [REPS]   (repetitions of the stage and output runs, default 3)
set -euo pipefail
cd "$(dirname "$0")/.."
REPS=${1:-3}
cargo build --release --workspace --all-targets --quiet
echo "== $(date -u +%FT%TZ) $(git rev-parse --short HEAD) load: $(cut -d' ' -f1-3 /proc/loadavg)"
cargo bench -p crash-core --bench shell_step -- --noplot >/dev/null 2>&1
python3 - <<'PY'
import json, pathlib
print("| element | stage | 1 thread | 2 threads | speed-up |")
print("| --- | --- | --- | --- | --- |")
for kind in ("Tri", "Quad"):
    for stage in ("internal_forces", "whole_step"):
        ns = []
        for t in (1, 2):
            d = pathlib.Path(f"target/criterion/{kind}_{t}t/{stage}")
            med = json.load(open(d / "new/estimates.json"))["median"]["point_estimate"]
            n = json.load(open(d / "new/benchmark.json"))["throughput"]["Elements"]
            ns.append(med / n)
        print(f"| {kind} ({n}) | {stage} | {ns[0]:.1f} | {ns[1]:.1f} | {ns[0] / ns[1]:.2f}x |")
PY
echo "== load: $(cut -d' ' -f1-3 /proc/loadavg)"
for s in "scenes/sphere-on-plate.toml 5e-3" "scenes/bench/openradioss-quad.toml 2e-3" \
  "scenes/bench/openradioss-tri.toml 2e-3"; do
  # shellcheck disable=SC2086
  cargo bench -p crash-tests --bench stages -- $s "$REPS" 2>/dev/null | grep -v '^rep '
  echo "== load: $(cut -d' ' -f1-3 /proc/loadavg)"
done
for p in f64 f32; do
  bash scripts/output-overhead.sh 2e-3 50 "$REPS" "$p"
  echo "== load: $(cut -d' ' -f1-3 /proc/loadavg)"
done
# the showcase as `crash run --threads 2` runs it (a domain per thread, since session 32)
# beside one worker whose two threads share the loops (the stages bench's 2 threads)
cargo bench -p crash-tests --bench scaling -- scenes/sphere-on-plate.toml 5e-3 "$REPS" 0,1,6 \
  2>/dev/null | grep -v '^rep '
echo "== load: $(cut -d' ' -f1-3 /proc/loadavg)"
