#!/usr/bin/env bash
# The reference pipeline's own convergence on the shipped scenes, for docs/BENCHMARKS.md:
#  - all orders (Monte Carlo): error against samples per pixel, against a 1024-spp reference;
#  - single term: the marcher's error against its sub-step, against step 0.125.
# Writes bench/out/*.csv and bench/out/reference-*.png. Usage: bench/reference-convergence.sh [SIZE]
set -euo pipefail
cd "$(dirname "$0")/.."
size=${1:-96}
out=bench/out
mkdir -p "$out"
for scene in sphere cube-torus layers bunny; do
  build/scatterd bench scenes/$scene.json --pipeline reference --terms all --width "$size" \
    --height "$size" --sweep spp=4,16,64,256 --reference-spp 1024 --frames 1 \
    --csv "$out/reference-all-$scene.csv"
  build/scatterd bench scenes/$scene.json --pipeline reference --terms single --width "$size" \
    --height "$size" --sweep step=2,1,0.5,0.25 --frames 3 --csv "$out/reference-single-$scene.csv"
done
bench/plot "$out/reference-all.png" "$out"/reference-all-*.csv
bench/plot "$out/reference-single.png" "$out"/reference-single-*.csv
