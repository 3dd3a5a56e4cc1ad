#!/usr/bin/env bash
# The cross-check (docs/crosscheck.md): run crash and the independent Python harness
# (tests/crosscheck/xcheck, numpy + mpi4py) on each scene of tests/crosscheck/scenes and
# compare positions, energies and contact forces; compare the harness with itself across
# rank counts.
#
#   bash tests/crosscheck/run.sh
#
# Environment:
#   CRASH_BIN         the crash binary [default: target/release/crash under the repo root]
#   CROSSCHECK_RANKS  MPI rank counts for the harness [default: "1 2 3"]
#   CROSSCHECK_OUT    run directories [default: out/crosscheck under the repo root]
#   CROSSCHECK_SCENES scene names to run [default: every tests/crosscheck/scenes/*.toml]
#
# Makes .venv-crosscheck/ at the repo root if it is missing (pip: numpy, mpi4py and the
# MPICH wheel, no system MPI; meshio for the frame-readability check).
# First checks that meshio reads crash's frames (vtu_meshio.py, f64 and f32). Prints one line per comparison and, last, exactly
# "N passed, M failed"; exits non-zero if anything failed.
set -u
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../.." && pwd)"
venv="$root/.venv-crosscheck"
crash="${CRASH_BIN:-$root/target/release/crash}"
ranks="${CROSSCHECK_RANKS:-1 2 3}"
out="${CROSSCHECK_OUT:-$root/out/crosscheck}"
passed=0
failed=0

line() {  # PASS|FAIL text
    echo "$1  $2"
    if [ "$1" = PASS ]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
}
finish() {
    echo "$passed passed, $failed failed"
    [ "$failed" -eq 0 ]
    exit $?
}

compare() {  # label ref run [tolerances]: one line per comparison
    local label="$1" ref="$2" run="$3" got=0 status rest
    shift 3
    while read -r status rest; do
        case "$status" in
            PASS|FAIL) line "$status" "$rest" ;;
            RESULT) got=1 ;;
        esac
    done < <("$py" "$here/compare.py" "$ref" "$run" --label "$label" "$@" 2>&1)
    [ "$got" = 1 ] || line FAIL "$label: the comparison did not complete"
}

# ---- the environment ----
py="$venv/bin/python"
if ! "$py" -c "import numpy, mpi4py, meshio" >/dev/null 2>&1; then
    echo "crosscheck: making $venv (numpy, mpi4py, mpich, meshio from PyPI)"
    { [ -x "$py" ] || python3 -m venv "$venv"; } &&
        "$venv/bin/pip" install --quiet --disable-pip-version-check numpy mpi4py mpich meshio ||
        { line FAIL "environment: could not make $venv"; finish; }
fi
mpiexec="$venv/bin/mpiexec"
hello="$("$mpiexec" -n 2 "$py" -c 'from mpi4py import MPI; c = MPI.COMM_WORLD; print(f"rank{c.Get_rank()}of{c.Get_size()}")' 2>&1)"
if ! { [[ "$hello" == *rank0of2* ]] && [[ "$hello" == *rank1of2* ]]; }; then
    line FAIL "environment: $mpiexec -n 2 does not run 2 MPI ranks: $hello"
    finish
fi
if [ ! -x "$crash" ]; then
    line FAIL "crash binary $crash not found (set CRASH_BIN or build target/release/crash)"
    finish
fi

# ---- the frames read by meshio (an independent VTU reader) ----
dump="$(dirname "$crash")/examples/vtu_dump"
if [ -x "$dump" ]; then
    compare_lines() {
        local status rest got=0
        while read -r status rest; do
            case "$status" in
                PASS|FAIL) line "$status" "$rest" ;;
                RESULT) got=1 ;;
            esac
        done < <("$@" 2>&1)
        [ "$got" = 1 ] || line FAIL "vtu meshio: the check did not complete"
    }
    compare_lines "$py" "$here/vtu_meshio.py" "$crash" "$dump" \
        "$root/scenes/sphere-on-plate-small.toml" "$out/vtu-meshio"
else
    line FAIL "vtu meshio: $dump not found (cargo build --release -p crash-io --examples)"
fi

# ---- the scenes ----
limit=""
if command -v timeout >/dev/null 2>&1; then limit="timeout 900"; fi
scenes="${CROSSCHECK_SCENES:-$(cd "$here/scenes" && ls *.toml | sed 's/\.toml$//')}"
first_rank="${ranks%% *}"
for s in $scenes; do
    toml="$here/scenes/$s.toml"
    dir="$out/$s"
    rm -rf "$dir"
    mkdir -p "$dir"
    if ! "$crash" run "$toml" --out "$dir/crash" --threads 1 --no-pictures --quiet >"$dir/crash.log" 2>&1; then
        # exit 3 (energy limit exceeded) still writes a complete run
        if [ ! -s "$dir/crash/energy.csv" ] || ! grep -q "done:" "$dir/crash.log"; then
            line FAIL "$s: crash run failed (see $dir/crash.log)"
            continue
        fi
    fi
    for n in $ranks; do
        start=$SECONDS
        # python -m mpi4py: an uncaught exception on any rank aborts the whole job (no
        # rank left waiting); the timeout is a last guard against a hang in CI
        if ! PYTHONPATH="$here" $limit "$mpiexec" -n "$n" "$py" -m mpi4py -m xcheck run "$toml" \
            --out "$dir/py-$n" >"$dir/py-$n.log" 2>&1; then
            line FAIL "$s ($n ranks): harness run failed (see $dir/py-$n.log)"
            continue
        fi
        echo "      $s: the harness on $n rank(s) took $((SECONDS - start)) s"
        compare "$s ($n ranks) vs crash" "$dir/crash" "$dir/py-$n"
        if [ "$n" != "$first_rank" ] && [ -d "$dir/py-$first_rank" ]; then
            compare "$s ($n vs $first_rank ranks)" "$dir/py-$first_rank" "$dir/py-$n" \
                --positions 1e-12 --energy 1e-12 --contact 1e-12
        fi
    done
done
finish
