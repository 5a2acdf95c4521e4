#!/usr/bin/env bash
# The reference's noise per setting `batch` (stratified batches, docs/pipelines/reference.md) on
# the issue's sphere at g 0 and 0.7 (the scenes bench/cycles/run.sh wrote to bench/out/cycles/:
# run it first): SEEDS renders (4) of SPP samples (256) per batch size, each reporting its
# noise (the relative norm of its standard error, from the batches' spread), against the noise
# they really have (the relative norm of the per-pixel spread across the seeds). Prints
# "g batch reported actual" lines. Usage: bench/cycles/batches.sh [BATCH...] (1 4 16 64)
# Environment: SPP (256), SEEDS (4), SCATTERD (build/scatterd).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=bench/out/cycles
spp=${SPP:-256}
seeds=${SEEDS:-4}
bin=${SCATTERD:-build/scatterd}
for g in 0 0.7; do
  for b in "${@:-1 4 16 64}"; do
    for b1 in $b; do
      files=()
      for s in $(seq 1 "$seeds"); do
        f="$out/batch-g$g-b$b1-$s.exr"
        "$bin" render "$out/sphere-g$g.json" --pipeline reference --terms all \
          --set spp="$spp" seed="$s" batch="$b1" --out "$f" >/dev/null
        files+=("$f")
      done
      /usr/bin/python3 - "$g" "$b1" "${files[@]}" <<'PY'
import sys
import numpy as np
import OpenImageIO as oiio

def read(path):
    img = oiio.ImageInput.open(path)
    px = np.asarray(img.read_image(format="float"), dtype=np.float64)[:, :, :3]
    img.close()
    return px

g, batch, paths = sys.argv[1], sys.argv[2], sys.argv[3:]
means = np.stack([read(p) for p in paths])
errors = [read(p.replace(".exr", ".stderr.exr")) for p in paths]
covered = means.mean(axis=0).max(axis=2) > 0
norm = np.linalg.norm(means.mean(axis=0)[covered])
reported = np.sqrt(np.mean([np.sum(e[covered] ** 2) for e in errors])) / norm
actual = np.linalg.norm(means.std(axis=0, ddof=1)[covered]) / norm
print(f"{g} {batch} reported {reported:.4f} actual {actual:.4f}")
PY
    done
  done
done
