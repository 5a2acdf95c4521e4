#!/usr/bin/env bash
# Figures for the `lbl` pipeline in docs/BENCHMARKS.md:
#  slab     R and T of the lattice against the reference's transport (tau 1-16, albedo 0.5-0.999,
#           g 0 and 0.75): bench/out/lbl-slab.csv
#  images   relative RMSE of the multiple and all terms against the reference path tracer on
#           sphere, layers and bunny at 128 x 128, 32^3 and 64^3 voxels, 6 and 18 directions,
#           and the multiple term at 128^3 with 6 directions
#           (global lattice); the paper's blocks (b 2, 4, 8, 4 steps per launch) on the sphere:
#           bench/out/lbl-*.csv
#  albedo   lattice steps to convergence against albedo (sigma_t 2.5 and 10 fixed): bench/out/lbl-albedo.csv
#  interleave marching and diffusion in rounds of k steps (Table I) against in sequence (k 0), 64^3
#  bandwidth the lattice step's GB/s against a STREAM-like copy in the same run (64^3, 128^3)
#  frames   light change against camera-only change at 512 x 512 in a live session
# Usage: bench/lbl.sh [SCATTERD] [PARTS...]
#   (parts: slab images albedo interleave bandwidth frames; default all)
set -euo pipefail
cd "$(dirname "$0")/.."
S=${1:-build/scatterd}
shift || true
parts=${*:-slab images albedo interleave bandwidth frames}
out=bench/out
mkdir -p "$out"
has() { [[ " $parts " == *" $1 "* ]]; }

if has slab; then
  echo "tau,albedo,g,R_ref,R_ref_stderr,R_lbl,R_err,T_ref,T_ref_stderr,T_lbl,T_err,lbl_steps" > "$out/lbl-slab.csv"
  for g in 0 0.75; do
    for tau in 1 2 4 8 16; do
      for a in 0.5 0.9 0.99 0.999; do
        ref=$($S slab --tau $tau --albedo $a --g $g --solver reference --photons 1000000 --json)
        lbl=$($S slab --tau $tau --albedo $a --g $g --solver lbl --json)
        jq -rn --argjson r "$ref" --argjson l "$lbl" --arg tau $tau --arg a $a --arg g $g \
          '[$tau, $a, $g, $r.R, $r.R_stderr, $l.R, ($l.R - $r.R), $r.T, $r.T_stderr, $l.T, ($l.T - $r.T), $l.steps] | @csv' \
          >> "$out/lbl-slab.csv"
      done
    done
  done
  echo "wrote $out/lbl-slab.csv"
fi

if has images; then
  for v in 32 64; do
    for scene in sphere layers bunny; do
      sed "s/\"voxels\": [0-9]*/\"voxels\": $v/" scenes/$scene.json > "$out/lbl-$scene-v$v.json"
      for terms in multiple all; do
        $S bench "$out/lbl-$scene-v$v.json" --pipeline lbl --terms $terms --width 128 --height 128 \
          --frames 1 --reference-spp 1024 --sweep directions=6,18 \
          --csv "$out/lbl-$scene-v$v-$terms.csv"
      done
    done
  done
  for scene in sphere layers bunny; do
    sed "s/\"voxels\": [0-9]*/\"voxels\": 128/" scenes/$scene.json > "$out/lbl-$scene-v128.json"
    $S bench "$out/lbl-$scene-v128.json" --pipeline lbl --terms multiple --width 128 --height 128 --frames 1 \
      --reference-spp 1024 --sweep directions=6 --csv "$out/lbl-$scene-v128-multiple.csv"
  done
  $S bench "$out/lbl-sphere-v64.json" --pipeline lbl --terms multiple --width 128 --height 128 --frames 1 \
    --reference-spp 1024 --set blocked=1 --set inner=4 --sweep block=2,4,8 --csv "$out/lbl-sphere-v64-block.csv"
fi

if has albedo; then
  # sigma_t 2.5 on 64^3 (the sphere is 5 mean free paths across) and 10 on 32^3 (20 across).
  echo "sigma_t,voxels,albedo,steps,diffuse_ms,converged" > "$out/lbl-albedo.csv"
  for st_v in 2.5:64 10:32; do
    st=${st_v%:*} v=${st_v#*:}
    for a in 0.5 0.8 0.9 0.95 0.98 0.99 0.995 0.999; do
      jq --argjson a $a --argjson st $st --argjson v $v \
        '.voxels = $v | .medium.sigma_s = [$st * $a, $st * $a, $st * $a] |
         .medium.sigma_a = [$st * (1 - $a), $st * (1 - $a), $st * (1 - $a)]' \
        scenes/sphere.json > "$out/lbl-albedo.json"
      $S render "$out/lbl-albedo.json" --pipeline lbl --terms multiple --width 64 --height 64 \
        --out "$out/lbl-albedo.exr" --json |
        jq -r --arg a $a --arg st $st --arg v $v '(.plan.stages[] | select(.stage == "diffuse") | .reason) as $r |
          [$st, $v, $a, ($r | capture("(in|after) (?<n>[0-9]+) steps").n), .timings_ms.diffuse, ($r | test("converged"))] | @csv' \
        >> "$out/lbl-albedo.csv"
    done
  done
  echo "wrote $out/lbl-albedo.csv"
fi

if has interleave; then
  # A cold lattice for each k (warm 0), one frame each: march and diffuse stage times.
  $S bench scenes/sphere.json --pipeline lbl --terms multiple --width 128 --height 128 --frames 1 \
    --reference-spp 1024 --set warm=0 --sweep interleave=0,2,4,8,16,32,64 --csv "$out/lbl-interleave.csv"
fi

if has bandwidth; then
  for v in 64 128; do
    sed "s/\"voxels\": 64/\"voxels\": $v/" scenes/sphere.json > "$out/lbl-bw-v$v.json"
    $S render "$out/lbl-bw-v$v.json" --pipeline lbl --terms multiple --width 64 --height 64 \
      --out "$out/lbl-bw.exr" --json --set measure=1 --set max_steps=64 |
      jq -r --arg v $v '"voxels \($v): " + (.plan.stages[] | select(.stage == "bandwidth") | .reason)'
  done | tee "$out/lbl-bandwidth.txt"
fi

if has frames; then
  port=18437
  $S serve --port $port > "$out/lbl-serve.log" 2>&1 &
  pid=$!
  trap 'kill $pid' EXIT
  sleep 1
  node --experimental-websocket bench/lbl-frames.mjs ws://127.0.0.1:$port/api/ws 6 sphere all 2>/dev/null |
    tee "$out/lbl-frames.txt"
fi
