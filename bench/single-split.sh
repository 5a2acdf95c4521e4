#!/usr/bin/env bash
# Figures for the `single` bake's split at extinction jumps and its weight solve
# (docs/BENCHMARKS.md, "Split at jumps"): relative RMSE of the single term at 256 x 256 and
# 25k samples against the reference marcher on each scene's own 64^3 grid (layers' and
# cube-torus's interfaces are planes, where the 64^3 grid is within 0.5 % of 256^3), with split,
# weight_fit and sigma_fit switched back one at a time; layers also at 50k; and the frame time at
# 512 x 512 with 1 and 8 lights (sphere). About 10 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
out=bench/out
mkdir -p "$out"
S=build/scatterd
for scene in layers cube-torus sphere bunny; do
  ref="$out/$scene-v64-single-256px.exr"
  view=(scenes/$scene.json --pipeline single --terms single --width 256 --height 256 --frames 3 --reference "$ref")
  $S bench "${view[@]}" --sweep samples=25000 --csv "$out/single-split-$scene-default.csv"
  case $scene in
    layers | cube-torus)
      $S bench "${view[@]}" --sweep split=0 --csv "$out/single-split-$scene-split.csv"
      $S bench "${view[@]}" --sweep weight_fit=0 --csv "$out/single-split-$scene-weight_fit.csv"
      $S bench "${view[@]}" --sweep sigma_fit=4 --csv "$out/single-split-$scene-sigma_fit.csv" ;;
  esac
done
$S bench scenes/layers.json --pipeline single --terms single --width 256 --height 256 --frames 3 \
  --reference "$out/layers-v64-single-256px.exr" --sweep samples=50000 --csv "$out/single-split-layers-50k.csv"
python3 bench/sphere-8lights.py "$out"
$S bench scenes/sphere.json --pipeline single --terms single --sweep samples=25000 --frames 9 \
  --csv "$out/single-split-512-1light.csv"
$S bench "$out/sphere-8lights.json" --pipeline single --terms single --sweep samples=25000 --frames 9 \
  --csv "$out/single-split-512-8lights.csv"
echo "done: $out/single-split-*.csv"
