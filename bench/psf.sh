#!/usr/bin/env bash
# Figures for the psf pipeline in docs/BENCHMARKS.md (about 40 minutes on 2 CPU cores):
#  (PART=errors or PART=time runs one half; PART=models the model 0 / model 1 table below;
#  PART=conserve model 1's conserve against its cap, after PART=models.)
#  - error of the multiple term (and of all terms) against the reference path tracer on sphere
#    (g 0 and 0.9, and albedo 0.5), layers and bunny, over the attenuation choice and the width
#    formula's shift, 128 x 128;
#  - the beam-spread width against Monte Carlo for two scattering coefficients (figure 4);
#  - precompute (light volume + pyramid) time at 64^3 and 128^3;
#  - frame time at 512 x 512 with 1 and 4 lights: camera-only change (volumes kept) and light
#    change (rebuild=1: every light's volume and pyramid rebuilt each frame).
set -euo pipefail
cd "$(dirname "$0")/.."
out=bench/out
S=${SCATTERD:-build/scatterd}  # a copy keeps a long run safe from rebuilds
mkdir -p "$out"
source bench/lib/install.sh
bench_install python3-numpy python3-openimageio  # bench/psf_compose_all.py
python3 - "$out" <<'PY'
import json, sys, math
out = sys.argv[1]
base = json.load(open("scenes/sphere.json"))
s = json.loads(json.dumps(base)); s["medium"]["g"] = 0.9
json.dump(s, open(f"{out}/sphere-g09.json", "w"))
s = json.loads(json.dumps(base)); s["medium"]["sigma_a"] = s["medium"]["sigma_s"]
json.dump(s, open(f"{out}/sphere-albedo05.json", "w"))
for v in (64, 128):
    s = json.loads(json.dumps(base)); s["voxels"] = v
    json.dump(s, open(f"{out}/sphere-v{v}.json", "w"))
s = json.loads(json.dumps(base))
light = s["lights"][0]
s["lights"] = [dict(light, position=[3 * math.cos(a), 2.0, 3 * math.sin(a)], intensity=light["intensity"] / 4)
               for a in (2 * math.pi * k / 4 for k in range(4))]
json.dump(s, open(f"{out}/sphere-4lights.json", "w"))
PY
small=(--width 128 --height 128 --frames 1)
part=${PART:-all}  # models | conserve | errors | time | all
# PART=models: the before/after table of docs/BENCHMARKS.md (issue 16): model 0 (the paper's) and
# model 1 (orders) against the reference on sphere (g 0, 0.7, 0.9), layers and bunny at 64 x 64,
# multiple term and all terms. Each reference is rendered once into bench/out/ref-<name>-<terms>-64.exr
# and reused (all = the marched single term + the Monte Carlo multiple term, bench/psf_compose_all.py).
if [ "$part" = models ]; then
  for g in 0.7 0.9; do
    python3 -c "import json,sys; s=json.load(open('scenes/sphere.json')); s['medium']['g']=$g; json.dump(s, open(sys.argv[1], 'w'))" "$out/sphere-g0${g#0.}.json"
  done
  for name in sphere sphere-g07 sphere-g09 layers bunny; do
    scene=scenes/$name.json; [ -f "$scene" ] || scene=$out/$name.json
    spp=4096; [ "$name" = sphere-g09 ] && spp=16384
    tiny=(--width 64 --height 64 --frames 1 --sweep model=0,1)
    $S bench "$scene" --pipeline psf --terms multiple "${tiny[@]}" --reference-spp $spp \
      --reference "$out/ref-$name-multiple-64.exr" --csv "$out/psf-$name-models-multiple.csv"
    $S bench "$scene" --pipeline psf --terms single "${tiny[@]}" \
      --reference "$out/ref-$name-single-64.exr" --csv "$out/psf-$name-models-single.csv"
    /usr/bin/python3 bench/psf_compose_all.py "$out/ref-$name-single-64.exr" \
      "$out/ref-$name-multiple-64.exr" "$out/ref-$name-all-64.exr"
    $S bench "$scene" --pipeline psf --terms all "${tiny[@]}" \
      --reference "$out/ref-$name-all-64.exr" --csv "$out/psf-$name-models-all.csv"
  done
  # Frame times at 512 x 512, 1 light: camera-only change and light change (rebuild=1).
  for m in 0 1; do
    $S bench scenes/sphere.json --pipeline psf --terms all --set model=$m --sweep rebuild=0,1 \
      --frames 3 --reference-spp 3 --reference "$out/ref-timing-512.exr" \
      --csv "$out/psf-512-model$m.csv"
  done
  echo "done: $out/psf-*-models-*.csv $out/psf-512-model*.csv"
  exit 0
fi
# PART=conserve: model 1's `conserve` against the capped orders (conserve=0) on the models
# table's references, and on layers of other density contrasts (15: 0.2 / 3, 30: 0.1 / 3) at
# 32 x 32 (their references rendered once, 4096 samples per pixel). Run PART=models first.
if [ "$part" = conserve ]; then
  for name in sphere sphere-g07 sphere-g09 layers bunny; do
    scene=scenes/$name.json; [ -f "$scene" ] || scene=$out/$name.json
    $S bench "$scene" --pipeline psf --terms multiple --width 64 --height 64 --frames 1 \
      --sweep conserve=0,1 --reference "$out/ref-$name-multiple-64.exr" \
      --csv "$out/psf-$name-conserve.csv"
  done
  for c in "15 0.2 3.0" "30 0.1 3.0"; do
    set -- $c
    python3 -c "import json,sys; s=json.load(open('scenes/layers.json')); s['medium']['density']['values']=[$2,$3]; json.dump(s, open(sys.argv[1], 'w'))" "$out/layers-c$1.json"
    $S bench "$out/layers-c$1.json" --pipeline psf --terms multiple --width 32 --height 32 \
      --frames 1 --sweep conserve=0,1 --reference-spp 4096 \
      --reference "$out/ref-layers-c$1-multiple-32.exr" --csv "$out/psf-layers-c$1-conserve.csv"
  done
  echo "done: $out/psf-*-conserve.csv"
  exit 0
fi
# (The sweeps below are model 0's, the paper's march: --set model=0.)
[ "$part" = time ] || for scene in scenes/sphere.json "$out/sphere-g09.json" "$out/sphere-albedo05.json" scenes/layers.json scenes/bunny.json; do
  name=$(basename "$scene" .json)
  spp=4096
  [ "$name" = sphere-g09 ] && spp=16384
  $S bench "$scene" --pipeline psf --terms multiple --set model=0 "${small[@]}" --reference-spp $spp \
    --sweep atten=0,1,2 --csv "$out/psf-$name-atten.csv"
  $S bench "$scene" --pipeline psf --terms multiple --set model=0 "${small[@]}" --reference-spp $spp \
    --sweep shift=0,2,8 --csv "$out/psf-$name-shift.csv"
  $S bench "$scene" --pipeline psf --terms all --set model=0 "${small[@]}" --reference-spp $spp \
    --sweep atten=0,2 --csv "$out/psf-$name-all.csv"
done
[ "$part" = errors ] && { echo "done: $out/psf-*.csv"; exit 0; }
$S beam --b 0.05 --a 0.0003 --g 0.9 --length 400 --photons 2000000 > "$out/psf-beam-b005.csv"
$S beam --b 0.2 --a 0.0003 --g 0.9 --length 100 --photons 2000000 > "$out/psf-beam-b02.csv"
for v in 64 128; do
  $S bench "$out/sphere-v$v.json" --pipeline psf --terms all --sweep rebuild=1 --frames 5 \
    --width 64 --height 64 --csv "$out/psf-precompute-v$v.csv"
done
for scene in scenes/sphere.json "$out/sphere-4lights.json"; do
  name=$(basename "$scene" .json)
  $S bench "$scene" --pipeline psf --terms all --sweep rebuild=0,1 --frames 5 --csv "$out/psf-512-$name.csv"
done
$S bench scenes/sphere.json --pipeline reference --terms single --sweep step=0.5 --frames 1 \
  --csv "$out/psf-512-marcher.csv"
echo "done: $out/psf-*.csv"
