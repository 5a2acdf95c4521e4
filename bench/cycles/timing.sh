#!/usr/bin/env bash
# Per-sample times of an earlier build of the reference, this one and Cycles, interleaved so that
# the machine's load falls on all three alike: ROUNDS rounds (3) at g 0 and 0.7 on the scenes
# bench/cycles/run.sh wrote to bench/out/cycles/ (run it first). Prints "who g wall cpu" lines:
# milliseconds per sample of wall clock (the reference's total_ms, Blender's frame time) and of
# CPU time (user + system, which a loaded machine disturbs less; each renderer's start-up, taken
# from a run of 4 samples, subtracted).
# Usage: bench/cycles/timing.sh BEFORE_SCATTERD   (e.g. /work/main/build/scatterd)
# Environment: ROUNDS (3), SPP_REF (512), SPP_CYCLES (256), CYCLES (1; 0: the two references
# alone, without Blender), AFTER (build/scatterd).
set -euo pipefail
cd "$(dirname "$0")/../.."
before=${1:?usage: bench/cycles/timing.sh BEFORE_SCATTERD}
out=bench/out/cycles
spp_ref=${SPP_REF:-512}
spp_cycles=${SPP_CYCLES:-256}
after=${AFTER:-build/scatterd}
cpu() { awk '{print $1 + $2}' "$out/timing-cpu.txt"; }
ref() {  # BINARY SCENE SPP: "wall-ms cpu-s"
  /usr/bin/time -f "%U %S" -o "$out/timing-cpu.txt" "$1" render "$2" --pipeline reference \
    --terms all --set spp="$3" seed=7 --out "$out/timing.exr" --json >"$out/timing.json"
  echo "$(/usr/bin/python3 -c "import json; print(json.load(open('$out/timing.json'))['total_ms'])") $(cpu)"
}
cycles() {  # G SPP: "wall-ms cpu-s"
  t=$(/usr/bin/time -f "%U %S" -o "$out/timing-cpu.txt" blender -b --factory-startup -noaudio \
    --python bench/cycles/scene.py -- --g "$1" --spp "$2" --seed 1 --out "$out/timing-cycles.exr" \
    2>&1 | sed -n 's/^ Time: \([0-9]*\):\([0-9.]*\) .*/\1 \2/p' | tail -1)
  echo "$(echo "$t" | awk '{print 1000 * ($1 * 60 + $2)}') $(cpu)"
}
per() {  # LABEL G "WALL CPU" "WALL4 CPU4" SPP
  echo "$1 $2 $3 $4 $5" | awk '{printf "%s %s wall %.2f cpu %.2f\n", $1, $2, $3 / $7, 1000 * ($4 - $6) / ($7 - 4)}'
}
for _ in $(seq 1 "${ROUNDS:-3}"); do
  for g in 0 0.7; do
    s=$out/sphere-g$g.json
    per before "$g" "$(ref "$before" "$s" "$spp_ref")" "$(ref "$before" "$s" 4)" "$spp_ref"
    per after "$g" "$(ref "$after" "$s" "$spp_ref")" "$(ref "$after" "$s" 4)" "$spp_ref"
    [ "${CYCLES:-1}" = 0 ] ||
      per cycles "$g" "$(cycles "$g" "$spp_cycles")" "$(cycles "$g" 4)" "$spp_cycles"
  done
done
