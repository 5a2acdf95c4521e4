#!/usr/bin/env bash
# Usage: bake.sh SCATTERD SOURCE_DIR OUT_DIR
# `scatterd bake`: a first bake misses the cache and stores the product on disk, a second finds it
# under the same key; a pipeline without a bake says so.
set -eu
scatterd=$1 src=$2 out=$3
rm -rf "$out" && mkdir -p "$out"
args=("$src/tests/cli/data/ok.json" --pipeline single --directions 16 --sh-order 3 --cache-dir "$out/cache" --json)
first=$("$scatterd" bake "${args[@]}" --samples 500)
grep -q '"cache_hit":false' <<<"$first" || { echo "FAIL: first bake was not a miss: $first"; exit 1; }
key=$(grep -oE '"key":"[0-9a-f]{64}"' <<<"$first" | cut -d'"' -f4)
[ -n "$key" ] || { echo "FAIL: no key in $first"; exit 1; }
[ -s "$out/cache/$key.bake" ] || { echo "FAIL: $out/cache/$key.bake not written"; exit 1; }
for stage in ddod divergence sampling gaussians sh; do
  grep -q "\"$stage\":" <<<"$first" || { echo "FAIL: no $stage time in $first"; exit 1; }
done
second=$("$scatterd" bake "${args[@]}" --samples 500)
grep -q '"cache_hit":true' <<<"$second" || { echo "FAIL: second bake was not a hit: $second"; exit 1; }
grep -q "\"key\":\"$key\"" <<<"$second" || { echo "FAIL: key changed: $second"; exit 1; }
other=$("$scatterd" bake "${args[@]}" --samples 600)
grep -q '"cache_hit":false' <<<"$other" || { echo "FAIL: other settings hit the cache: $other"; exit 1; }
none=$("$scatterd" bake "$src/tests/cli/data/ok.json" --pipeline surface --cache-dir "$out/cache" --json)
grep -q '"needed":false' <<<"$none" || { echo "FAIL: surface claims a bake: $none"; exit 1; }
echo "ok: $key"
