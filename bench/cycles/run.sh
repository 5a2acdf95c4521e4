#!/usr/bin/env bash
# The reference against Blender's Cycles on the issue's sphere (bench/cycles/sphere.json; the
# Blender scene is built by bench/cycles/scene.py), at g 0 and 0.7, for docs/BENCHMARKS.md:
#  - the reference at SPP_REF samples per pixel in stratified batches of BATCH (its mean and
#    per-pixel standard error, from the batches' spread);
#  - Cycles RUNS times at SPP_CYCLES with other seeds (their mean, and its standard error from
#    their spread; the Z-test takes Student's t at Welch-Satterthwaite's degrees of freedom);
#  - the two compared pixel by pixel (bench/cycles/compare.py: relative RMSE, a per-pixel Z-test
#    with Sidak correction), each one's noise per sample and its time to 5 % and 2 % noise
#    (render time per sample x the samples that noise needs, noise falling as 1/sqrt(samples)).
# Installs Blender (Debian's, 3.4), numpy and OpenImageIO's Python module on demand: they are
# the benchmark's dependencies, not the project's. Usage: bench/cycles/run.sh [G...]
# Environment: SPP_REF (1024), BATCH (16), SPP_CYCLES (128), RUNS (8). Results: bench/out/cycles/.
set -euo pipefail
cd "$(dirname "$0")/../.."
spp_ref=${SPP_REF:-1024}
spp_cycles=${SPP_CYCLES:-128}
runs=${RUNS:-8}
# The reference's stratified batches (its setting `batch`): its standard error rests on
# spp / batch independent batch means, the degrees of freedom the Z-test takes.
batch=${BATCH:-16}
out=bench/out/cycles
mkdir -p "$out"
py=/usr/bin/python3

source bench/lib/install.sh
bench_install blender python3-numpy python3-openimageio

echo "| g | reference noise (spp) | Cycles noise (spp) | rRMSE apart | Z-test pass | reference ms/spp | Cycles ms/spp | time to 5 %: reference / Cycles | time to 2 % |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
for g in "${@:-0 0.7}"; do
  for g1 in $g; do
    scene="$out/sphere-g$g1.json"
    sed "s/\"g\": 0.0/\"g\": $g1/" bench/cycles/sphere.json >"$scene"
    build/scatterd render "$scene" --pipeline reference --terms all --set spp="$spp_ref" seed=7 \
      batch="$batch" \
      --out "$out/ref-g$g1.exr" --json >"$out/ref-g$g1.json"
    times=()
    files=()
    for i in $(seq 1 "$runs"); do
      f="$out/cycles-g$g1-$i.exr"
      log=$(blender -b --factory-startup -noaudio --python bench/cycles/scene.py -- --g "$g1" \
        --spp "$spp_cycles" --seed "$i" --out "$f" 2>&1)
      # Blender's " Time: mm:ss.ss (Saving: ...)": the frame's render time, without start-up.
      times+=("$(echo "$log" | sed -n 's/^ Time: \([0-9]*\):\([0-9.]*\) .*/\1 \2/p' | tail -1)")
      files+=("$f")
    done
    combined=$($py bench/cycles/combine.py "$out/cycles-g$g1.exr" "${files[@]}")
    cmp=$($py bench/cycles/compare.py "$out/ref-g$g1.exr" "$out/cycles-g$g1.exr" \
      --a-err "$out/ref-g$g1.stderr.exr" --b-err "$out/cycles-g$g1.stderr.exr" --a-n "$((spp_ref / batch))" \
      --b-n "$runs")
    echo "$cmp" >"$out/compare-g$g1.json"
    $py - "$g1" "$spp_ref" "$spp_cycles" "$out/ref-g$g1.json" "$combined" "$cmp" "${times[@]}" <<'PY'
import json, sys
g, spp_ref, spp_c = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
ref = json.load(open(sys.argv[4]))
comb, cmp = json.loads(sys.argv[5]), json.loads(sys.argv[6])
times = [int(m) * 60 + float(s) for m, s in (t.split() for t in sys.argv[7:])]
ms_ref = ref["total_ms"] / spp_ref
ms_c = 1000 * sorted(times)[len(times) // 2] / spp_c  # the median run
n_ref, n_c = ref["error_estimate"], comb["noise_one"]
def to(target, ms, noise, spp):
    return ms * spp * (noise / target) ** 2 / 1000
cells = [g, f"{n_ref:.4f} ({spp_ref})", f"{n_c:.4f} ({spp_c})", f"{cmp['rrmse']:.4f}",
         f"{100 * cmp['z_pass']:.2f} %", f"{ms_ref:.1f}", f"{ms_c:.1f}"]
for target in (0.05, 0.02):
    r, c = to(target, ms_ref, n_ref, spp_ref), to(target, ms_c, n_c, spp_c)
    cells.append(f"{r:.1f} s / {c:.1f} s ({r / c:.2f}x)")
print("| " + " | ".join(cells) + " |")
PY
  done
done
