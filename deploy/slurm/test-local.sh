#!/usr/bin/env bash
# Check crash.sbatch's wiring without Slurm: stand-ins for `scontrol show hostnames`
# (3 nodes, all this machine) and `srun` (starts --ntasks copies of the command here)
# run the script as the batch step would, on 127.0.0.1 and a free port: 1 master and
# 3 workers (one per node). The run must
# finish with the same final state hash as `crash run` on the same scene.
#
#   deploy/slurm/test-local.sh          (uses target/release, or CRASH_BIN; build it first)
set -euo pipefail
cd "$(dirname "$0")/../.."
repo="$PWD"
scene="scenes/ten-spheres-three-plates-small.toml"

tmp="$(mktemp -d "${TMPDIR:-/tmp}/crash-slurm.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/bin"

cat >"$tmp/bin/scontrol" <<'EOF'
#!/usr/bin/env bash
# stand-in: `scontrol show hostnames LIST` -> three nodes, all of them this machine
[ "$1 $2" = "show hostnames" ] || { echo "scontrol stand-in: unsupported: $*" >&2; exit 1; }
printf '127.0.0.1\n127.0.0.1\n127.0.0.1\n'
EOF
cat >"$tmp/bin/srun" <<'EOF'
#!/usr/bin/env bash
# stand-in: run the command --ntasks times here, wait for all; TERM is passed on
n=1
while [ $# -gt 0 ]; do
  case "$1" in
    --ntasks=*) n="${1#--ntasks=}"; shift ;;
    --*) shift ;;
    *) break ;;
  esac
done
pids=()
for _ in $(seq "$n"); do "$@" & pids+=($!); done
trap 'kill -TERM "${pids[@]}" 2>/dev/null' TERM
rc=0
for p in "${pids[@]}"; do wait "$p" || rc=$?; done
exit "$rc"
EOF
chmod +x "$tmp/bin/scontrol" "$tmp/bin/srun"

port="$(python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"

rc=0
env PATH="$tmp/bin:$PATH" SLURM_JOB_ID=42 SLURM_JOB_NODELIST='node[01-03]' \
  SLURM_SUBMIT_DIR="$repo" SLURM_CPUS_PER_TASK=1 CRASH_PORT="$port" \
  timeout 120 bash deploy/slurm/crash.sbatch "$scene" "$tmp/slurm" >"$tmp/job.log" 2>&1 || rc=$?
"${CRASH_BIN:-target/release}/crash" run "$scene" --out "$tmp/local" --workers 3 --threads 1 --quiet --no-pictures \
  >"$tmp/local.log" 2>&1 || true

hash_of() { sed -n 's/.*"final_state_hash": *"\([0-9a-f]*\)".*/\1/p' "$1/summary.json" 2>/dev/null; }
job_hash="$(hash_of "$tmp/slurm")"
local_hash="$(hash_of "$tmp/local")"
attached="$(grep -c 'attached to http://127.0.0.1' "$tmp/job.log" || true)"
if [ "$rc" = 0 ] && [ "$attached" = 3 ] && [ -n "$local_hash" ] && [ "$job_hash" = "$local_hash" ]; then
  echo "slurm-local: PASS: final_state_hash job=$job_hash local=$local_hash (3 workers attached, one per node)"
else
  cat "$tmp/job.log" >&2
  echo "slurm-local: FAIL: exit $rc, $attached workers attached, final_state_hash job=${job_hash:-none} local=${local_hash:-none}"
  exit 1
fi
