#!/bin/bash
# Session 12 (docs/scaling.md, "The barrier taken apart"): run master + 2 workers of the
# binaries in BINDIR on SCENE to END with CRASH_LEGS set (binaries built with
# stamps.patch applied write per-step timestamps; analyse with legs.py /tmp/legs-TAG).
# usage: barrier_legs.sh BINDIR SCENE END TAG [extra master/worker args]
BIN=$1; SCENE=$2; END=$3; TAG=$4; shift 4
EXTRA="$@"
OUT=/tmp/bl-out-$TAG; rm -rf $OUT /tmp/legs-$TAG.*
export CRASH_LEGS=/tmp/legs-$TAG RUST_LOG=warn
$BIN/crash-master $SCENE --listen 127.0.0.1:0 --split off --workers 2 --out $OUT --end-time $END --output-interval $END $EXTRA 2> /tmp/bl-master-$TAG.err &
MP=$!
for i in $(seq 50); do ADDR=$(grep -o 'listening on .*' /tmp/bl-master-$TAG.err | awk '{print $3}'); [ -n "$ADDR" ] && break; sleep 0.1; done
$BIN/crash-worker --master http://$ADDR --threads 1 $EXTRA 2>/dev/null &
W1=$!
$BIN/crash-worker --master http://$ADDR --threads 1 $EXTRA 2>/dev/null &
W2=$!
wait $MP; wait $W1; wait $W2
python3 -c "
import json;s=json.load(open('$OUT/summary.json'));print('wall',s['wall_time_s'],'steps',s['steps'],'hash',s.get('final_state_hash',s.get('state_hash')));print(s['barrier_us_per_step'])"
