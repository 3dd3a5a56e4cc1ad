#!/usr/bin/env bash
# The whole test suite: one release build shared by every test (unit, physics, cluster,
# end to end), then the docker-compose smoke test when a Docker engine answers.
set -euo pipefail
cd "$(dirname "$0")/.."

command -v cargo >/dev/null || { echo "cargo not found: install Rust (rustup) first" >&2; exit 1; }

export CARGO_TERM_COLOR=never
cargo build --release --workspace --all-targets
cargo test --release --workspace --no-fail-fast -- --test-threads 2

# The independent cross-check (docs/crosscheck.md): the documented equations written
# again in Python (numpy + mpi4py from wheels, in .venv-crosscheck/), on 2 MPI ranks.
CROSSCHECK_RANKS=2 bash tests/crosscheck/run.sh

if [ -x deploy/compose-smoke.sh ]; then
  if docker info >/dev/null 2>&1; then
    # --no-build: the image takes the binaries built above (a `cargo build -p` here
    # would resolve features differently and rebuild them)
    deploy/compose-smoke.sh --no-build
  else
    echo "SKIP: docker-compose smoke test: no Docker engine answers 'docker info'"
  fi
fi
