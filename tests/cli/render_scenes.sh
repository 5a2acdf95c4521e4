#!/usr/bin/env bash
# Usage: render_scenes.sh SCATTERD SOURCE_DIR OUT_DIR
# Renders every shipped scene with the surface pipeline to PNG and checks the file is a 512x512 PNG
# and that --json reports the plan and the stage timings.
set -eu
scatterd=$1 src=$2 out=$3
mkdir -p "$out"
for scene in "$src"/scenes/*.json; do
  name=$(basename "$scene" .json)
  json=$("$scatterd" render "$scene" --pipeline surface --out "$out/$name.png" --json)
  grep -q '"pipeline":"surface"' <<<"$json" || { echo "FAIL $name: no pipeline in $json"; exit 1; }
  grep -q '"timings_ms":{' <<<"$json" || { echo "FAIL $name: no timings in $json"; exit 1; }
  # PNG signature, then IHDR width and height as big-endian 32-bit integers at bytes 16..23.
  size=$(od -An -tu1 -j16 -N8 "$out/$name.png" | tr -s ' ')
  [ "$size" = " 0 0 2 0 0 0 2 0" ] || { echo "FAIL $name: not 512x512 ($size)"; exit 1; }
  echo "ok: $name: $json"
done
