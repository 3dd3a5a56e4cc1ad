#!/bin/bash
# Session 36 (docs/performance.md, "Session 36"): run crash-master --split auto + 2
# crash-worker x 1 thread of the binaries in BINDIR on SCENE to END with CRASH_STAMPS set
# (binaries built with stamps.patch applied: `git apply scripts/barrier-legs/stamps.patch
# && cargo build --release -p crash-master -p crash-worker`, BINDIR a copy of
# target/release), then print the legs (legs.py).
# usage: run.sh BINDIR SCENE END
BIN=$1; SCENE=$2; END=$3
OUT=$(mktemp -d); ST=$(mktemp -d)
export CRASH_STAMPS=$ST
$BIN/crash-master "$SCENE" --listen 127.0.0.1:7496 --split auto --workers 2 --out $OUT/run --end-time $END --output-interval $END 2>$OUT/master.log &
sleep 0.3
$BIN/crash-worker --master http://127.0.0.1:7496 --threads 1 2>/dev/null &
$BIN/crash-worker --master http://127.0.0.1:7496 --threads 1 2>/dev/null &
wait
python3 "$(dirname "$0")/legs.py" $ST
rm -rf $OUT $ST
