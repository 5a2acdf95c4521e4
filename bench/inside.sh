#!/usr/bin/env bash
# The camera inside the object (docs/BENCHMARKS.md, "The camera inside the object"): single and
# thickness against the reference's single term on a homogeneous box seen from inside (two eye
# heights) and from outside, and single on the bunny seen from inside its body; 64 x 64.
set -euo pipefail
cd "$(dirname "$0")/.."
out=bench/out/inside
mkdir -p "$out"
box() {  # name, camera position, target, fov
  cat > "$out/$1.json" <<JSON
{"mesh": {"shape": "box", "size": [2, 2, 2]},
 "medium": {"sigma_s": 0.8, "sigma_a": 0.2, "g": 0.3},
 "lights": [{"type": "directional", "direction": [0, 0, -1], "irradiance": 2.0}],
 "camera": {"position": $2, "target": $3, "fov_deg": $4},
 "image": {"width": 64, "height": 64}, "voxels": 32}
JSON
}
box box-in-0.5 "[0, 0, 0.5]" "[0, 0, -1]" 60
box box-in--0.5 "[0, 0, -0.5]" "[0, 0, -1]" 60
box box-out "[0, 0, 4]" "[0, 0, 0]" 30
python3 - "$out" <<'PY'
import json, sys
s = json.load(open('scenes/bunny.json'))
s['camera'] = {'position': [0, -0.1, 0.1], 'target': [0, 0, -1], 'fov_deg': 70}
s['image'] = {'width': 64, 'height': 64}
s['voxels'] = 32
json.dump(s, open(sys.argv[1] + '/bunny-in.json', 'w'))
PY
for scene in box-in-0.5 box-in--0.5 box-out bunny-in; do
  pipelines="single"
  [[ $scene == box* ]] && pipelines="single thickness"
  for p in $pipelines; do
    sweep=samples=25000
    [[ $p == thickness ]] && sweep=steps=32
    build/scatterd bench "$out/$scene.json" --pipeline "$p" --terms single --frames 3 --sweep "$sweep" \
      --reference "$out/ref-$scene.exr" --csv "$out/$p-$scene.csv"
  done
done
for f in "$out"/*.csv; do tail -n +2 "$f"; done | cut -d, -f1,2,9,11
