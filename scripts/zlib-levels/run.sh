#!/bin/bash
# The zlib-rs levels on the Float64 arrays of a mid-run frame of the floor:
#   bash scripts/zlib-levels/run.sh [FRAME_NO]   (default 16)
# Runs the floor to 1 ms with a frame every 50 steps and `compression = "none"`, cuts
# the arrays out of one frame and compresses each at levels 1 and 2.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$here/../.."
k="${1:-16}"
tmp="$(mktemp -d)"
cp "$root/scenes/bench/spheres-on-deformable-plate.toml" "$tmp/floor.toml"
printf '\n[outputs]\ncompression = "none"\n' >> "$tmp/floor.toml"
cargo run --release -q --manifest-path "$root/Cargo.toml" -p crash-cli -- run "$tmp/floor.toml" \
  --end-time 1e-3 --output-interval 2.4e-5 --out "$tmp/out" --no-pictures > /dev/null
python3 "$here/split_arrays.py" "$(printf '%s/out/frames/frame_%06d.vtu' "$tmp" "$k")" "$tmp/arr" > /dev/null
cargo run --release -q --manifest-path "$here/Cargo.toml" -- "$tmp"/arr/*.Float64
