#!/usr/bin/env bash
# docker-compose smoke test: build the image, run a scene on the compose cluster
# (1 master + 2 workers), run the same scene locally with `crash run`, and require the
# same final state hash (summary.json) from both. Tears the cluster down on every exit.
#
#   deploy/compose-smoke.sh [--no-build]
#
# --no-build: use target/release as it is (scripts/test.sh has just built it).
# Environment: CRASH_SMOKE_SCENE (a file in scenes/) [ten-spheres-three-plates-small.toml],
#              CRASH_SMOKE_TIMEOUT (seconds for the cluster run) [180].
set -euo pipefail
cd "$(dirname "$0")/.."
repo="$PWD"

build_flag=()
for arg in "$@"; do
  case "$arg" in
    --no-build) build_flag=(--no-build) ;;
    *) echo "compose-smoke: unknown argument $arg" >&2; exit 2 ;;
  esac
done

scene="${CRASH_SMOKE_SCENE:-ten-spheres-three-plates-small.toml}"
timeout_s="${CRASH_SMOKE_TIMEOUT:-180}"
workers=2
image="crash:smoke"
project="crash-smoke-$$"

if docker compose version >/dev/null 2>&1; then
  compose=(docker compose)
elif command -v docker-compose >/dev/null 2>&1; then
  compose=(docker-compose)
else
  echo "SKIP: docker-compose smoke test: neither 'docker compose' nor 'docker-compose' is installed"
  exit 0
fi

now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
# Wait until container $1 has stopped, at most $2 seconds (docker wait cannot be
# bounded: the docker client outlives a SIGTERM from timeout).
wait_exit() {
  local end=$((SECONDS + $2))
  while [ "$(docker inspect -f '{{.State.Running}}' "$1" 2>/dev/null)" = true ]; do
    [ "$SECONDS" -lt "$end" ] || return 1
    sleep 0.2
  done
}
hash_of() { sed -n 's/.*"final_state_hash": *"\([0-9a-f]*\)".*/\1/p' "$1/summary.json" 2>/dev/null; }

tmp="$(mktemp -d "${TMPDIR:-/tmp}/crash-smoke.XXXXXX")"
mkdir -p "$tmp/local" "$tmp/cluster"
uid="$(id -u)"
gid="$(id -g)"
# a fresh shared secret: the workers prove it, the master admits only them
CRASH_SECRET="$(head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n')"
export CRASH_SECRET
export CRASH_IMAGE="$image" CRASH_SCENES="$repo/scenes" CRASH_SCENE="$scene" \
  CRASH_OUT="$tmp/cluster" CRASH_WORKERS="$workers" CRASH_THREADS=1 \
  CRASH_UID="$uid" CRASH_GID="$gid"
dc() { "${compose[@]}" -p "$project" -f "$repo/deploy/docker-compose.yml" "$@"; }

cleanup() {
  dc down -t 2 --remove-orphans >/dev/null 2>&1 || true
  rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

fail() {
  echo "compose-smoke: $1" >&2
  dc ps -a >&2 || true
  dc logs --no-color --tail=40 >&2 || true
  echo "compose-smoke: FAIL: $2"
  exit 1
}

t0="$(now)"
deploy/build-image.sh "${build_flag[@]}" "$image"
t_image="$(since "$t0")"

# The reference: the same binaries, in one process, on the host.
t1="$(now)"
rc=0
target/release/crash run "scenes/$scene" --out "$tmp/local" --workers "$workers" --threads 1 \
  --quiet --no-pictures >"$tmp/local.log" 2>&1 || rc=$?
t_local="$(since "$t1")"
# exit 3 = the run finished over the scene's energy-balance limit: its hash still counts
if [ "$rc" != 0 ] && [ "$rc" != 3 ]; then
  cat "$tmp/local.log" >&2
  echo "compose-smoke: FAIL: the local run 'crash run scenes/$scene' exited with $rc"
  exit 1
fi
local_hash="$(hash_of "$tmp/local")"

t2="$(now)"
dc up -d --no-color --scale "worker=$workers" >"$tmp/up.log" 2>&1 || { cat "$tmp/up.log" >&2; fail "docker-compose up failed" "the cluster did not start"; }
master="$(dc ps -a -q master)"
[ -n "$master" ] || fail "no master container" "the cluster did not start"
started="$(dc ps -a -q worker | wc -l)"
[ "$started" = "$workers" ] || fail "$started worker containers, expected $workers" "wrong number of workers"

# The master exits when the run is over; bound the wait.
wait_exit "$master" "$timeout_s" ||
  fail "the master did not finish within $timeout_s s" "timeout"
t_cluster="$(since "$t2")"
master_rc="$(docker inspect -f '{{.State.ExitCode}}' "$master")"
[ "$master_rc" = 0 ] || fail "crash-master exited with $master_rc" "the cluster run failed"
# Workers are told to shut down by the master: they must be gone, with exit code 0.
for w in $(dc ps -a -q worker); do
  wait_exit "$w" 15 || fail "worker $w still runs after the master ended" "no clean shutdown"
  wrc="$(docker inspect -f '{{.State.ExitCode}}' "$w")"
  [ "$wrc" = 0 ] || fail "worker $w exited with $wrc" "a worker failed"
done
cluster_hash="$(hash_of "$tmp/cluster")"

summary="local=${local_hash:-none} cluster=${cluster_hash:-none} (scene $scene, $workers workers; image ${t_image} s, local run ${t_local} s, cluster run ${t_cluster} s)"
if [ -n "$local_hash" ] && [ "$local_hash" = "$cluster_hash" ]; then
  echo "compose-smoke: PASS: final_state_hash $summary"
else
  fail "the final state hashes differ" "final_state_hash $summary"
fi
