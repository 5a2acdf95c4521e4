#!/usr/bin/env bash
# Figures for the `single` pipeline's defaults beyond the paper (docs/BENCHMARKS.md, "exact
# transmittance and its model over each Gaussian"): relative RMSE of the single term at 256 x 256
#  - against the reference marcher on a 256^3 grid of the same scene (the converged reference;
#    the scene's own 64^3 grid carries a staircase silhouette on curved meshes), over samples
#    5k-100k with today's defaults, and at 25k samples against the 64^3 grid as well;
#  - with each of tr_gradient, tr_hessian and adapt switched back (25k samples);
#  - frame time at 512 x 512 with 1 and 8 lights (sphere).
# Takes about 25 minutes on 2 cores (the 256^3 references about 10 of them; they are kept).
set -euo pipefail
cd "$(dirname "$0")/.."
out=bench/out
mkdir -p "$out"
S=build/scatterd
for scene in sphere cube-torus layers bunny; do
  ref="$out/$scene-v256-single-256px.exr"
  if [ ! -f "$ref" ]; then
    sed 's/"voxels": 64/"voxels": 256/' "scenes/$scene.json" > "$out/$scene-v256.json"
    $S render "$out/$scene-v256.json" --pipeline reference --terms single --width 256 --height 256 --out "$ref"
  fi
  view=(scenes/$scene.json --pipeline single --terms single --width 256 --height 256 --frames 3)
  $S bench "${view[@]}" --reference "$ref" --sweep samples=5000,10000,25000,50000,100000 \
    --csv "$out/single-exact-$scene-samples.csv"
  $S bench "${view[@]}" --sweep samples=25000 --csv "$out/single-exact-$scene-v64.csv"
  for sweep in tr_gradient=0,1 tr_hessian=0,1 adapt=1,0.5; do
    $S bench "${view[@]}" --reference "$ref" --sweep "$sweep" --csv "$out/single-exact-$scene-${sweep%%=*}.csv"
  done
done
bench/plot "$out/single-exact-samples.png" "$out"/single-exact-*-samples.csv

# Frame time: 1 and 8 lights.
python3 bench/sphere-8lights.py "$out"
$S bench scenes/sphere.json --pipeline single --terms single --sweep samples=25000 --frames 9 \
  --csv "$out/single-exact-512-1light.csv"
$S bench "$out/sphere-8lights.json" --pipeline single --terms single --sweep samples=25000 --frames 9 \
  --csv "$out/single-exact-512-8lights.csv"
echo "done: $out/single-exact-*.csv"
