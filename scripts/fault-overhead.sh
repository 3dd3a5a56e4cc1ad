#!/usr/bin/env bash
# What fault tolerance costs a run without faults (docs/reliability.md): interleaved runs
# of ten-spheres-three-plates-small to 4 ms on crash-master + 2 crash-worker (1 thread
# each, loopback), printing wall time, summed user+sys CPU time and the output stage
# (checkpoints + frames). Needs `cargo build --release -p crash-master -p crash-worker`.
# Usage: [END=seconds] [SHORT=1] scripts/fault-overhead.sh [ROUNDS]
# (END: the run's end time, default 0.004; SHORT: only off, default and every1s)
set -euo pipefail
cd "$(dirname "$0")/.."
T=target/release
ROUNDS=${1:-5}
END=${END:-0.004}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

one() { # TAG master-args...
  local tag=$1 out=$TMP/$1
  shift
  rm -rf "$out"; mkdir -p "$out"
  /usr/bin/time -f "%U %S" -o "$out/tm" $T/crash-master scenes/ten-spheres-three-plates-small.toml \
    --listen 127.0.0.1:0 --workers 2 --out "$out/run" --end-time "$END" --estimated-costs "$@" 2>"$out/m.log" &
  for _ in $(seq 100); do grep -q "listening on" "$out/m.log" && break; sleep 0.1; done
  local addr
  addr=$(grep -o "listening on .*" "$out/m.log" | awk '{print $3}')
  /usr/bin/time -f "%U %S" -o "$out/t1" $T/crash-worker --master "http://$addr" --threads 1 2>/dev/null &
  /usr/bin/time -f "%U %S" -o "$out/t2" $T/crash-worker --master "http://$addr" --threads 1 2>/dev/null &
  wait
  python3 - "$out" "$tag" <<'PY'
import json, sys
out, tag = sys.argv[1], sys.argv[2]
s = json.load(open(out + "/run/summary.json"))
cpu = sum(sum(map(float, open(out + "/" + f).read().split()[-2:])) for f in ("tm", "t1", "t2"))
out_s = s["ns_per_element_cycle"]["output"] * s["elements"] * s["steps"] / 1e9
print(f"{tag:10} wall {s['wall_time_s']:7.2f} s  cpu {cpu:6.2f} s  output stage {out_s:6.3f} s")
PY
}

for _ in $(seq "$ROUNDS"); do
  one off --checkpoint-seconds 0 --heartbeat-timeout 0
  one default
  one every1s --checkpoint-seconds 1
  if [ -z "${SHORT:-}" ]; then
    # the cost of one checkpoint: many of them, frames only at the start and end
    one frameless --checkpoint-seconds 0 --heartbeat-timeout 0 --output-interval 1
    one ck0.2 --checkpoint-seconds 0.2 --output-interval 1
  fi
done
