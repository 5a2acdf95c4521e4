#!/usr/bin/env bash
# Usage: render_scenes.sh SCATTERD SOURCE_DIR OUT_DIR
# Renders every shipped scene with the surface pipeline to PNG and checks the file is a 512x512 PNG
# with the object in view and lit, and that --json reports the plan and the stage timings.
set -eu
scatterd=$1 src=$2 out=$3
mkdir -p "$out"
for scene in "$src"/scenes/*.json; do
  name=$(basename "$scene" .json)
  json=$("$scatterd" render "$scene" --pipeline surface --out "$out/$name.png" --json)
  grep -q '"pipeline":"surface"' <<<"$json" || { echo "FAIL $name: no pipeline in $json"; exit 1; }
  grep -q '"timings_ms":{' <<<"$json" || { echo "FAIL $name: no timings in $json"; exit 1; }
  # The object covers a good part of the frame and is lit: coverage above 5 %, a non-zero mean.
  coverage=$(grep -oE '"coverage":[0-9.e-]+' <<<"$json" | cut -d: -f2)
  awk -v c="$coverage" 'BEGIN { exit !(c > 0.05 && c < 0.95) }' ||
    { echo "FAIL $name: coverage $coverage"; exit 1; }
  mean=$(grep -oE '"mean":\[[^]]*\]' <<<"$json" | sed -E 's/"mean":\[(.*)\]/\1/')
  awk -v m="$mean" 'BEGIN { split(m, a, ","); exit !(a[1] + a[2] + a[3] > 1e-4) }' ||
    { echo "FAIL $name: black image (mean $mean)"; exit 1; }
  # PNG signature, then IHDR width and height as big-endian 32-bit integers at bytes 16..23.
  size=$(od -An -tu1 -j16 -N8 "$out/$name.png" | tr -s ' ')
  [ "$size" = " 0 0 2 0 0 0 2 0" ] || { echo "FAIL $name: not 512x512 ($size)"; exit 1; }
  echo "ok: $name: $json"
done
