#!/usr/bin/env bash
# Configures and builds the fuzz targets with clang into BUILD_DIR (ctest's fuzz.build).
# Usage: build.sh BUILD_DIR [MAIN_BUILD_DIR]   (MAIN_BUILD_DIR: for fuzz_rest; empty skips it)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
build="$1"
main="${2:-}"
mkdir -p "$build"
if ! cmake -S "$here" -B "$build" -DCMAKE_CXX_COMPILER=clang++-14 -DSCATTER_MAIN_BUILD="$main" \
    >"$build/configure.log" 2>&1; then
  cat "$build/configure.log" >&2
  exit 1
fi
if ! cmake --build "$build" -j "${SCATTER_JOBS:-$(nproc)}" >"$build/build.log" 2>&1; then
  grep -E -A5 'error' "$build/build.log" | head -60 >&2
  echo "fuzz build failed (log: $build/build.log)" >&2
  exit 1
fi
echo "fuzz targets built in $build"
