#!/usr/bin/env bash
# Figures for the thickness path in docs/BENCHMARKS.md:
#  - error against the reference single term on sphere.json as the reference's voxels get finer
#    (128 x 128 pixels; the 256^3 reference takes a few minutes);
#  - frame time at 512 x 512 with 1 and 8 point lights.
set -euo pipefail
cd "$(dirname "$0")/.."
out=bench/out
mkdir -p "$out"
for v in 64 128 256; do
  sed "s/\"voxels\": 64/\"voxels\": $v/" scenes/sphere.json > "$out/sphere-v$v.json"
  build/scatterd bench "$out/sphere-v$v.json" --pipeline thickness --terms single --width 128 \
    --height 128 --sweep steps=8,32 --csv "$out/thickness-sphere-v$v.csv"
done
python3 bench/sphere-8lights.py "$out"
build/scatterd bench scenes/sphere.json --pipeline thickness --terms single --sweep steps=32 \
  --frames 7 --csv "$out/thickness-512-1light.csv"
build/scatterd bench "$out/sphere-8lights.json" --pipeline thickness --terms single --sweep steps=32 \
  --frames 7 --csv "$out/thickness-512-8lights.csv"
