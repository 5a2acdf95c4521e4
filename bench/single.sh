#!/usr/bin/env bash
# Figures for the `single` pipeline in docs/BENCHMARKS.md (the paper's Table 1 as curves):
#  - error of the single term against the reference marcher on sphere, cube-torus, layers and bunny
#    at 256 x 256, swept over samples (5k-100k), directions (32-512) and SH bands (2-5), each sweep
#    holding the others at 25k samples, 128 directions, 5 bands;
#  - the SH of optical depth (exponentiated when rendering) against the paper's SH of transmittance,
#    and clipping at the second surface against the paper's front-only clipping;
#  - exact transmittance (exact_tr, the default), SH up to 8 bands, the density guide, sigma_fit;
#  - bake time per stage at 64^3 and 128^3 voxels (128 directions, 25k samples);
#  - frame time at 512 x 512 with 1 and 8 lights, and the reference marcher's at the same size.
# Bakes go to a memory-only cache so every bake is timed. Takes about 45 minutes on 2 cores.
set -euo pipefail
cd "$(dirname "$0")/.."
out=bench/out
mkdir -p "$out"
S=build/scatterd
base=(--set samples=25000 --set directions=128 --set sh_order=5)
for scene in sphere cube-torus layers bunny; do
  # The paper's path (SH of transmittance, its sample spacing) for the sweeps of its parameters;
  # exact_tr is swept below (today's other defaults: bench/single-exact.sh).
  view=(scenes/$scene.json --pipeline single --terms single --width 256 --height 256 --frames 3)
  common=("${view[@]}" --set exact_tr=0 --set adapt=1)
  $S bench "${common[@]}" --set directions=128 --set sh_order=5 --sweep samples=5000,10000,25000,50000,100000 \
    --csv "$out/single-$scene-samples.csv"
  $S bench "${common[@]}" --set samples=25000 --set sh_order=5 --sweep directions=32,64,128,256,512 \
    --csv "$out/single-$scene-directions.csv"
  $S bench "${common[@]}" --set samples=25000 --set directions=128 --sweep sh_order=2,3,4,5 \
    --csv "$out/single-$scene-sh.csv"
  $S bench "${common[@]}" "${base[@]}" --sweep sh_depth=0,1 --csv "$out/single-$scene-shdepth.csv"
  $S bench "${common[@]}" "${base[@]}" --sweep clip_back=0,1 --csv "$out/single-$scene-clip.csv"
  # Beyond the paper: exact transmittance instead of the SH, SH beyond 5 bands, density guide.
  $S bench "${view[@]}" "${base[@]}" --sweep exact_tr=0,1 --csv "$out/single-$scene-exact.csv"
  $S bench "${common[@]}" --set samples=25000 --set directions=128 --sweep sh_order=5,6,8 \
    --csv "$out/single-$scene-sh-high.csv"
  $S bench "${common[@]}" "${base[@]}" --sweep density_guide=0,1 --csv "$out/single-$scene-guide.csv"
  $S bench "${view[@]}" "${base[@]}" --set exact_tr=1 --sweep sigma_fit=0,4 --csv "$out/single-$scene-fit.csv"
done
bench/plot "$out/single-samples.png" "$out"/single-*-samples.csv

# Bake stages at two grid resolutions.
for v in 64 128; do
  sed "s/\"voxels\": 64/\"voxels\": $v/" scenes/bunny.json > "$out/bunny-v$v.json"
  $S bake "$out/bunny-v$v.json" --pipeline single --directions 128 --samples 25000 --cache-dir none --json \
    > "$out/single-bake-v$v.json"
done

# Frame time: 1 and 8 lights.
python3 bench/sphere-8lights.py "$out"
$S bench scenes/sphere.json --pipeline single --terms single "${base[@]}" --sweep exact_tr=0,1 --frames 9 \
  --csv "$out/single-512-1light.csv"
$S bench "$out/sphere-8lights.json" --pipeline single --terms single "${base[@]}" --sweep exact_tr=0,1 --frames 9 \
  --csv "$out/single-512-8lights.csv"
for i in 1 2 3; do
  $S render scenes/sphere.json --pipeline reference --terms single --out "$out/ref-512.exr" --json
done > "$out/reference-512-march.jsonl"
echo "done: $out/single-*.csv, single-bake-v*.json, reference-512-march.jsonl"
