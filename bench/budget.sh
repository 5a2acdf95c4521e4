#!/usr/bin/env bash
# Figures for the budget planner in docs/BENCHMARKS.md ("Choosing by error budget"):
#  1. every calibrated way (pipeline and quality, composites) on the four shipped scenes at
#     SIZE x SIZE: frame time against relative RMSE, as a table (bench/out/pareto.json) and a
#     plot per terms (docs/pareto-<terms>.png);
#  2. what auto picks for budgets of 1 %, 5 % and 20 % on each shipped scene, and the error it
#     reached against the reference (bench/out/budget-*.csv).
# The shipped scenes are not calibration scenes. At SIZE 64 the first half takes about 4 minutes
# on a 2-core CPU, the second about 5; BUDGET_ONLY=1 runs the second alone (what auto picks
# depends on the calibration table, the Pareto plot only on the pipelines).
set -euo pipefail
cd "$(dirname "$0")/.."
out=bench/out
size=${SIZE:-64}
mkdir -p "$out"
if [ -z "${BUDGET_ONLY:-}" ]; then
  build/scatterd bench --calibrate "$out/pareto.json" --size "$size" --max-spp 2048 \
    scenes/sphere.json scenes/cube-torus.json scenes/layers.json scenes/bunny.json
  python3 bench/pareto.py "$out/pareto.json" docs
fi
# The single term's reference is deterministic (the marcher at step 0.125), so 1 % can be checked;
# all terms at 1 % would need ~1e5 samples per pixel of the path tracer (the daemon refuses it
# past --max-render-s), so all terms are measured at 5 % and 20 % against a 2048-spp reference.
for scene in sphere cube-torus layers bunny; do
  for run in single:0.2 single:0.05 single:0.01 all:0.2 all:0.05; do
    terms=${run%%:*} budget=${run##*:}
    build/scatterd bench "scenes/$scene.json" --pipeline auto --terms "$terms" --width "$size" \
      --height "$size" --sweep seed=1 --max-error "$budget" --frames 1 --reference-spp 2048 \
      --csv "$out/budget-$scene-$terms-$budget.csv"
  done
done
python3 - "$out" <<'PY'
import csv, glob, os, sys
print("| scene | terms | budget | auto chose | frame | error reached | reference noise | error without it |")
print("| --- | --- | --- | --- | --- | --- | --- | --- |")
for f in sorted(glob.glob(os.path.join(sys.argv[1], "budget-*.csv"))):
    for r in csv.DictReader(open(f)):
        budget = f.rsplit("-", 1)[1][:-4]  # budget-SCENE-TERMS-BUDGET.csv
        print(f"| {r['scene']} | {r['terms']} | {float(budget) * 100:g} % | {r['pipeline']} | "
              f"{float(r['frame_ms_median']):.0f} ms | {float(r['rel_rmse']) * 100:.2f} % | "
              f"{float(r['reference_noise']) * 100:.2f} % | "
              f"{max(0, float(r['rel_rmse'])**2 - float(r['reference_noise'])**2)**0.5 * 100:.2f} % |")
PY
