#!/usr/bin/env bash
# Per-sample times of an earlier build of the reference, this one and Cycles, interleaved so that
# the machine's load falls on all three alike: ROUNDS rounds (3) at g 0 and 0.7 on the scenes
# bench/cycles/run.sh wrote to bench/out/cycles/ (run it first). Prints "who g ms-per-sample" lines.
# Usage: bench/cycles/timing.sh BEFORE_SCATTERD   (e.g. /work/main/build/scatterd)
set -euo pipefail
cd "$(dirname "$0")/../.."
before=${1:?usage: bench/cycles/timing.sh BEFORE_SCATTERD}
out=bench/out/cycles
ms() { /usr/bin/python3 -c "import json,sys; print(json.load(sys.stdin)['total_ms'] / $1)"; }
for _ in $(seq 1 "${ROUNDS:-3}"); do
  for g in 0 0.7; do
    s=$out/sphere-g$g.json
    echo "before $g $("$before" render "$s" --pipeline reference --terms all --set spp=512 seed=7 \
      --out "$out/timing-before.exr" --json | ms 512)"
    echo "after $g $(build/scatterd render "$s" --pipeline reference --terms all --set spp=512 \
      seed=7 --out "$out/timing-after.exr" --json | ms 512)"
    t=$(blender -b --factory-startup -noaudio --python bench/cycles/scene.py -- --g "$g" --spp 256 \
      --seed 1 --out "$out/timing-cycles.exr" 2>&1 |
      sed -n 's/^ Time: \([0-9]*\):\([0-9.]*\) .*/\1 \2/p' | tail -1)
    echo "cycles $g $(echo "$t" | awk '{print 1000 * ($1 * 60 + $2) / 256}')"
  done
done
