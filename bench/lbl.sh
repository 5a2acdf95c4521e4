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
#  targets  issue 16's targets: all and single terms at 64 voxels, 64 x 64, on the four shipped
#           scenes and the sphere at g 0.7 and 0.9, against references rendered once and kept
#           (bench/out/ref-NAME.exr: 2048 spp, 8192 at g 0.7 and 0.9; ref-NAME.single.exr):
#           bench/out/lbl-targets.csv (SET="k=v ..." adds lbl settings)
#  slab-targets  the slab at tau 2-8, albedo 0.9 and 0.99, g 0 and 0.75, mu0 1 and 0.1, relative
#           differences: bench/out/lbl-targets-slab.csv (SLAB="--scaled-view 1" or "--orders N"
#           adds the lbl slab's options)
# Usage: bench/lbl.sh [SCATTERD] [PARTS...]
#   (parts: slab images albedo interleave bandwidth frames targets slab-targets; default the
#   first six)
set -euo pipefail
cd "$(dirname "$0")/.."
S=${1:-build/scatterd}
shift || true
parts=${*:-slab images albedo interleave bandwidth frames}
sets=()
for kv in ${SET:-}; do sets+=(--set "$kv"); done
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

if has targets; then
  # name:scene:g (empty g: the scene's own) and the references' samples per pixel.
  cases="sphere:sphere: cube-torus:cube-torus: layers:layers: bunny:bunny: sphere-g0.7:sphere:0.7
         sphere-g0.9:sphere:0.9"
  echo "name,terms,rel_rmse,reference_noise,frame_ms,stages" > "$out/lbl-targets.csv"
  for c in $cases; do
    IFS=: read -r name scene g <<< "$c"
    json="$out/lbl-target-$name.json"
    jq --arg g "$g" '.voxels = 64 | if $g != "" then .medium.g = ($g | tonumber) else . end' \
      scenes/$scene.json > "$json"
    spp=2048
    [ -n "$g" ] && spp=8192
    for terms in single all; do
      ref="$out/ref-$name.exr"
      [ $terms = single ] && ref="$out/ref-$name.single.exr"
      nice -n 5 $S bench "$json" --pipeline lbl --terms $terms --width 64 --height 64 --frames 1 \
        --reference "$ref" --reference-spp $spp --sweep warm=1 "${sets[@]}" \
        --csv "$out/lbl-target-$name-$terms.csv" > /dev/null
      tail -n 1 "$out/lbl-target-$name-$terms.csv" | awk -F, -v n=$name -v t=$terms \
        '{ print n "," t "," $11 "," $12 "," $9 "," $13 }' >> "$out/lbl-targets.csv"
    done
  done
  column -s, -t "$out/lbl-targets.csv"
fi

if has slab-targets; then
  echo "tau,albedo,g,mu0,R_ref,R_lbl,R_rel,T_ref,T_lbl,T_rel" > "$out/lbl-targets-slab.csv"
  for mu0 in 1 0.1; do
    for g in 0 0.75; do
      for tau in 2 4 8; do
        for a in 0.9 0.99; do
          ref=$($S slab --tau $tau --albedo $a --g $g --mu0 $mu0 --solver reference --photons 400000 --json)
          lbl=$($S slab --tau $tau --albedo $a --g $g --mu0 $mu0 --solver lbl ${SLAB:-} --json)
          jq -rn --argjson r "$ref" --argjson l "$lbl" --arg tau $tau --arg a $a --arg g $g --arg m $mu0 \
            '[$tau, $a, $g, $m, $r.R, $l.R, ($l.R / $r.R - 1), $r.T, $l.T, ($l.T / $r.T - 1)] | @csv' \
            >> "$out/lbl-targets-slab.csv"
        done
      done
    done
  done
  column -s, -t "$out/lbl-targets-slab.csv"
fi
