#!/usr/bin/env bash
# Budgets on scenes off the calibration grid, for docs/BENCHMARKS.md ("Budgets off the
# calibration grid"): 14 scenes drawn at random (seeded: sphere or box, albedo 0.5-0.99, tau
# 0.7-18, g -0.9-0.9, ior 1/1.3/1.6, constant or noise density; 24 x 24 px, 32 voxels), auto at
# all terms 20 % and 10 % and the multiple term 20 %, each against a 32768-spp path-traced
# reference (kept in bench/out/survey/refs, so a second binary reuses them). Prints a table;
# "over" marks an error past its budget once the reference's noise is taken out in quadrature.
# Usage: bench/budget-survey.sh [SCATTERD] [TAG]. About 15 minutes on a 2-core CPU, most of it the
# references (rendered once: a later run takes about 2 minutes).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/scatterd}
tag=${2:-now}
out=bench/out/survey
mkdir -p "$out/scenes" "$out/refs" "$out/$tag"
python3 - "$out/scenes" <<'PY'
import json, math, random, sys
r = random.Random(20261207)
for i in range(14):
    shape = r.choice(['sphere', 'box'])
    albedo = 1 - 10 ** r.uniform(-2, -0.3)
    tau = 2 ** r.uniform(-0.5, 4.2)
    g = round(r.uniform(-0.9, 0.9), 2)
    ior = r.choice([1, 1, 1.3, 1.6])
    dens = r.choice(['constant', 'constant', 'noise'])
    st = tau / (2 * (0.6 if dens == 'noise' else 1))
    mesh = ({'shape': 'sphere', 'radius': 1.0} if shape == 'sphere'
            else {'shape': 'box', 'size': [2, 2, 2]})
    d = ({'type': 'noise', 'scale': 2.0, 'min': 0.2, 'max': 1.0, 'seed': 11} if dens == 'noise'
         else {'type': 'constant'})
    ang = r.uniform(0, 6.28)
    s = {'mesh': mesh,
         'medium': {'sigma_s': [st * albedo] * 3, 'sigma_a': [st * (1 - albedo)] * 3, 'g': g,
                    'ior': ior, 'density': d},
         'lights': [{'type': 'point', 'position': [3 * math.cos(ang), 2.5, 3 * math.sin(ang) + 1],
                     'color': [1, 1, 1], 'intensity': 20}],
         'camera': {'position': [0.3, 0.5, 4], 'target': [0, 0, 0], 'up': [0, 1, 0],
                    'fov_deg': 45},
         'image': {'width': 24, 'height': 24}, 'voxels': 32}
    name = f's{i:02d}-{shape}-a{albedo:.3f}-t{tau:.1f}-g{g}-ior{ior}-{dens}'
    json.dump(s, open(f'{sys.argv[1]}/{name}.json', 'w'))
PY
for f in "$out"/scenes/*.json; do
  n=$(basename "$f" .json)
  for run in all:0.2 all:0.1 multiple:0.2; do
    terms=${run%%:*} budget=${run##*:}
    "$bin" bench "$f" --pipeline auto --terms "$terms" --sweep seed=1 --max-error "$budget" \
      --frames 1 --reference "$out/refs/$n-$terms.exr" --reference-spp 32768 \
      --csv "$out/$tag/$n-$terms-$budget.csv" > "$out/$tag/$n-$terms-$budget.log" 2>&1 ||
      echo "failed: $n $terms $budget (see $out/$tag/$n-$terms-$budget.log)" >&2
  done
done
python3 - "$out/$tag" <<'PY'
import csv, glob, os, sys
print("| scene | terms | budget | auto chose | frame | error reached | reference noise | |")
print("| --- | --- | --- | --- | --- | --- | --- | --- |")
over = runs = 0
for f in sorted(glob.glob(os.path.join(sys.argv[1], "*.csv"))):
    scene, terms, budget = os.path.basename(f)[:-4].rsplit("-", 2)
    rows = list(csv.DictReader(open(f)))
    if not rows:
        continue
    r = rows[-1]
    e, n, b = float(r['rel_rmse']), float(r['reference_noise']), float(budget)
    d = max(0.0, e * e - n * n) ** 0.5
    runs += 1
    over += d > b
    print(f"| {scene} | {terms} | {b * 100:g} % | {r['pipeline'].replace('auto -> ', '')} | "
          f"{float(r['frame_ms_median']):.0f} ms | {d * 100:.2f} % | {n * 100:.2f} % | "
          f"{'over' if d > b else ''} |")
print(f"\n{over} of {runs} runs over their budget")
PY
