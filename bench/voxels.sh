#!/usr/bin/env bash
# Error against time of lbl and psf (all terms) on each shipped scene at 32, 64 and 128 voxels
# (docs/BENCHMARKS.md, "lbl and psf against their grid"): 64 x 64 pixels, one cold first frame
# each (volume or bake, march and diffusion or pyramid, view), relative RMSE over the covered
# pixels against the mesh-bounded reference at the scene's own 64 voxels (2048 samples per pixel,
# seed 7919: bench/out/ref-NAME.exr, the file `bench/lbl.sh BIN targets` renders and keeps), so
# the error at each grid is against one ground truth. About 15 minutes on 2 cores.
# Output: bench/out/voxels.csv (pipeline, scene, voxels, rel_rmse, reference noise, bake ms,
# frame ms, stages). Usage: bench/voxels.sh [SCATTERD] (VOXELS="32 64 128", SCENES, PIPELINES to narrow).
set -euo pipefail
cd "$(dirname "$0")/.."
S=${1:-build/scatterd}
out=bench/out
mkdir -p "$out"
csv="$out/voxels.csv"
echo "pipeline,scene,voxels,rel_rmse,reference_noise,bake_ms,frame_ms,stages" > "$csv"
for scene in ${SCENES:-sphere cube-torus layers bunny}; do
  ref="$out/ref-$scene.exr"
  if [ ! -f "$ref" ]; then  # bench renders a missing reference from the scene it is given
    jq '.voxels = 64' "scenes/$scene.json" > "$out/voxels-$scene-ref.json"
    nice -n 5 "$S" bench "$out/voxels-$scene-ref.json" --pipeline lbl --terms all --width 64 \
      --height 64 --frames 1 --reference "$ref" --reference-spp 2048 --sweep warm=1 \
      --csv "$out/voxels-one.csv" > /dev/null
  fi
  for v in ${VOXELS:-32 64 128}; do
    json="$out/voxels-$scene-$v.json"
    jq --argjson v "$v" '.voxels = $v' "scenes/$scene.json" > "$json"
    for p in ${PIPELINES:-lbl psf}; do
      # A setting swept over its default alone: bench needs one, the render is the default's.
      sweep="warm=1"
      [ "$p" = psf ] && sweep="model=1"
      nice -n 5 "$S" bench "$json" --pipeline "$p" --terms all --width 64 --height 64 --frames 1 \
        --reference "$ref" --reference-spp 2048 --sweep "$sweep" --csv "$out/voxels-one.csv" \
        > /dev/null
      tail -n 1 "$out/voxels-one.csv" | awk -F, -v p="$p" -v n="$scene" -v v="$v" \
        '{ print p "," n "," v "," $11 "," $12 "," $8 "," $9 "," $13 }' >> "$csv"
    done
  done
done
column -s, -t "$csv"
