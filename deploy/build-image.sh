#!/usr/bin/env bash
# Build the crash container image FROM scratch: the release binaries plus the shared
# libraries they load (as `ldd` lists them, the dynamic loader included), copied at
# their host paths. Needs only cargo and docker (ldd comes with the C library;
# strip, from binutils, is used when present to drop debug info).
#
#   deploy/build-image.sh [--no-build] [TAG]      (TAG default: $CRASH_IMAGE or crash:latest)
#
# --no-build uses target/release as it is (the binaries must exist); otherwise the
# release build is brought up to date first (a no-op when CI already built it).
set -euo pipefail
cd "$(dirname "$0")/.."

build=1
tag="${CRASH_IMAGE:-crash:latest}"
for arg in "$@"; do
  case "$arg" in
    --no-build) build=0 ;;
    -h|--help) sed -n '2,11p' "$0"; exit 0 ;;
    -*) echo "build-image: unknown option $arg" >&2; exit 2 ;;
    *) tag="$arg" ;;
  esac
done

bins=(crash crash-master crash-worker)
if [ "$build" = 1 ]; then
  cargo build --release -p crash-cli -p crash-master -p crash-worker
fi
# cargo's target dir (CARGO_TARGET_DIR may move it)
target="${CARGO_TARGET_DIR:-target}"
for b in "${bins[@]}"; do
  [ -x "$target/release/$b" ] || { echo "build-image: $target/release/$b is missing: run cargo build --release first" >&2; exit 1; }
done

ctx="$(mktemp -d "${TMPDIR:-/tmp}/crash-image.XXXXXX")"
trap 'rm -rf "$ctx"' EXIT
root="$ctx/rootfs"
mkdir -p "$root/usr/local/bin" "$root/etc" "$root/tmp"
chmod 1777 "$root/tmp"

# Copy one file (following symlinks) to the same path under rootfs/.
copy_at_path() {
  mkdir -p "$root$(dirname "$1")"
  cp -L "$1" "$root$1"
}

for b in "${bins[@]}"; do
  if command -v strip >/dev/null; then
    strip --strip-debug -o "$root/usr/local/bin/$b" "$target/release/$b"
  else
    cp "$target/release/$b" "$root/usr/local/bin/$b"
  fi
  # ldd lines: "libm.so.6 => /lib/x86_64-linux-gnu/libm.so.6 (0x...)" and
  # "/lib64/ld-linux-x86-64.so.2 (0x...)"; the vDSO has no file. A static
  # binary prints "not a dynamic executable" / "statically linked": nothing to copy.
  while read -r lib; do
    [ -n "$lib" ] && [ -e "$lib" ] && copy_at_path "$lib"
  done < <(ldd "$target/release/$b" 2>/dev/null | awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// { print $1 }' | sort -u)
done

# Name resolution (workers dial http://master:50051): glibc's files and dns
# back ends are built into libc.so.6; docker mounts /etc/hosts and /etc/resolv.conf.
printf 'hosts: files dns\n' > "$root/etc/nsswitch.conf"

version="$(sed -n 's/^version = "\(.*\)"/\1/p' Cargo.toml | head -n 1)"
revision="$(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
{
  cat deploy/Dockerfile
  printf 'LABEL org.opencontainers.image.title="crash" org.opencontainers.image.version="%s" org.opencontainers.image.revision="%s"\n' \
    "${version:-unknown}" "$revision"
} >"$ctx/Dockerfile"
echo "build-image: context $(du -sh "$root" | cut -f1) ($(find "$root" -type f | wc -l) files)"
old_id="$(docker image inspect -f '{{.Id}}' "$tag" 2>/dev/null || true)"
docker build --quiet \
  -t "$tag" "$ctx" >"$ctx/build.log" 2>&1 || { cat "$ctx/build.log" >&2; exit 1; }
# the image this tag named before, if nothing else names it now, is only garbage
new_id="$(docker image inspect -f '{{.Id}}' "$tag")"
if [ -n "$old_id" ] && [ "$old_id" != "$new_id" ] &&
  [ "$(docker image inspect -f '{{len .RepoTags}}' "$old_id" 2>/dev/null)" = 0 ]; then
  docker rmi "$old_id" >/dev/null 2>&1 || true
fi
docker image ls "$tag" --format 'build-image: {{.Repository}}:{{.Tag}} {{.ID}} {{.Size}}'
