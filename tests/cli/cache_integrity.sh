#!/usr/bin/env bash
# Usage: cache_integrity.sh SCATTERD SOURCE_DIR OUT_DIR
# The daemon's bake cache survives what happens to files on disk:
#  - kill -9 during a bake, restart on the same --cache-dir: the daemon answers, the bake asked
#    again completes and a render after it (also after another restart) comes from the cache;
#  - a writer killed mid-write leaves a temporary file: it is never taken for the product;
#  - a .bake truncated, with bytes flipped in the middle, with another product's header, or
#    another key's whole file: detected, counted in /metrics as corrupt, moved aside and re-baked;
#    the render after it is the same image as before the damage.
set -euo pipefail
scatterd=$1 src=$2 out=$3
rm -rf "$out" && mkdir -p "$out"
# shellcheck source=tests/cli/daemon_lib.sh
source "$(dirname "$0")/daemon_lib.sh"
trap stop_all EXIT
cache=$out/cache

# A small inline scene: bakes of about a second, and a slower one (more samples and directions)
# to be killed while it runs. exact_tr=0 only makes the renders cheaper; it is not a bake setting.
scene='{"mesh": {"shape": "sphere", "radius": 1},
  "medium": {"sigma_s": [2, 2, 2], "sigma_a": [0.05, 0.05, 0.05],
             "density": {"type": "noise", "scale": 2, "octaves": 2, "min": 0.3, "max": 1.2}},
  "lights": [{"type": "point", "position": [3, 3, 3], "color": [1, 1, 1], "intensity": 20}],
  "camera": {"position": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 40},
  "image": {"width": 48, "height": 48}, "voxels": 32}'
fast='{"samples": 2000, "directions": 16, "sh_order": 3}'
slow='{"samples": 8000, "directions": 48, "sh_order": 3}'
bake_body() { echo "{\"scene\": $scene, \"pipeline\": \"single\", \"settings\": $1}"; }
render_body() { echo "{\"scene\": $scene, \"pipeline\": \"single\", \"terms\": \"single\", \"settings\": ${1%\}}, \"exact_tr\": 0}}"; }

start() { start_daemon d "$scatterd" --scenes-dir "$src/scenes" --cache-dir "$cache"; port=${daemon_port[d]}; }

# bake SETTINGS: posts the bake and waits for it; sets `job` (its final status) and `key`.
bake() {
  api "$port" POST /api/bakes "$(bake_body "$1")"
  [[ $status == 20[02] ]] || fail "POST /api/bakes: status $status: $reply"
  wait_bake "$port" "$(json_field "$reply" id)"
  job=$reply key=$(json_field "$reply" key)
  [[ $key =~ ^[0-9a-f]{64}$ ]] || fail "no key in $job"
}

# render SETTINGS FILE: a PNG of the scene; sets `timings` (X-Scatter-Timings).
render() {
  api "$port" POST /api/render "$(render_body "$1")" -D "$out/headers"
  [ "$status" = 200 ] || fail "POST /api/render: status $status: $reply"
  cp "$out/reply" "$2"
  timings=$(grep -i '^X-Scatter-Timings:' "$out/headers" | cut -d' ' -f2- | tr -d '\r')
}

expect_from_cache() {  # the render found its product: a "cache" stage and no "bake" stage
  grep -q '"cache":' <<<"$timings" && ! grep -q '"bake":' <<<"$timings" ||
    fail "$1: the render did not come from the cache: timings $timings"
}

# ---- a first bake, the reference image -----------------------------------------------------
start
bake "$fast"
[ "$(json_field "$job" cache_hit)" = false ] || fail "first bake on an empty cache was a hit: $job"
fast_key=$key
[ -s "$cache/$fast_key.bake" ] || fail "$cache/$fast_key.bake not written"
render "$fast" "$out/reference.png"
expect_from_cache "render after the bake"
cp "$cache/$fast_key.bake" "$out/fast.bake.good"

# ---- kill -9 during a bake -----------------------------------------------------------------
api "$port" POST /api/bakes "$(bake_body "$slow")"
[ "$status" = 202 ] || fail "POST of the slow bake: status $status: $reply"
slow_id=$(json_field "$reply" id)
deadline=$((SECONDS + 30))
while :; do  # running, and past the voxelization: inside the bake proper
  api "$port" GET "/api/bakes/$slow_id"
  [ "$(json_field "$reply" state)" = running ] && [ "$(json_field "$reply" stage)" != voxelize ] && break
  [ "$(json_field "$reply" state)" != done ] || fail "the slow bake finished before it could be killed: $reply"
  [ $SECONDS -lt $deadline ] || fail "the slow bake did not start running within 30 s: $reply"
  sleep 0.05
done
stop_daemon d KILL
echo "killed during: $reply"
# What a writer killed between write and rename leaves behind: half a file under a temporary name.
# The product itself is gone, so only the temporary file could answer for it.
rm "$cache/$fast_key.bake"
head -c $(($(stat -c %s "$out/fast.bake.good") / 2)) "$out/fast.bake.good" >"$cache/$fast_key.bake.tmp-999999-0"
start
for route in /api/health /api/assets /api/bakes /api/pipelines; do
  api "$port" GET "$route"
  [ "$status" = 200 ] || fail "after kill -9 and restart, GET $route: status $status: $reply"
done
bake "$slow"
[ "$(json_field "$job" cache_hit)" = false ] || fail "the killed bake was found in the cache: $job"
slow_key=$key
[ -s "$cache/$slow_key.bake" ] || fail "the completed slow bake wrote no $slow_key.bake"
api "$port" POST /api/bakes "$(bake_body "$slow")"
[ "$status" = 200 ] && [ "$(json_field "$reply" state)" = done ] ||
  fail "the same bake asked again is not the finished job: status $status: $reply"
render "$slow" "$out/slow.png"
expect_from_cache "render after the bake completed past a kill -9"
bake "$fast"
[ "$(json_field "$job" cache_hit)" = false ] || fail "a leftover temporary file was taken for the product: $job"
render "$fast" "$out/fast-after-temp.png"
cmp -s "$out/reference.png" "$out/fast-after-temp.png" || fail "re-baked after a torn write: the image differs"
stop_daemon d
# Once more after a clean restart: the product comes from disk.
start
render "$slow" "$out/slow-again.png"
expect_from_cache "render after a restart"
[ "$(metric "$port" 'scatter_bake_cache_lookups_total{result="disk_hit"}')" = 1 ] ||
  fail "the render after a restart was not a disk hit: $(metric "$port" 'scatter_bake_cache_lookups_total{result="disk_hit"}') disk hits"
cmp -s "$out/slow.png" "$out/slow-again.png" || fail "the render from disk differs from the one before the restart"
stop_daemon d
echo "ok: kill -9 during a bake ($slow_id), restart, bake completed ($slow_key), renders from the cache"

# ---- damaged files -------------------------------------------------------------------------
# damage MODE FILE: what can happen to a file on disk.
size=$(stat -c %s "$out/fast.bake.good")
damage() {
  case $1 in
    truncated) truncate -s $((size / 2)) "$2" ;;
    flipped)  # 16 bytes in the middle of the payload, inverted
      perl -e 'open(my $f, "+<", $ARGV[0]) or die; binmode $f; seek($f, $ARGV[1], 0); read($f, my $b, 16);
               seek($f, $ARGV[1], 0); print $f ($b ^ ("\xff" x 16));' "$2" $((size / 2)) ;;
    header)  # the header (magic, version, size, key, checksum: 84 bytes) of the other product
      dd if="$cache/$slow_key.bake" of="$2" bs=84 count=1 conv=notrunc status=none ;;
    swapped) cp "$cache/$slow_key.bake" "$2" ;;  # another key's whole, valid file
  esac
}
for mode in truncated flipped header swapped; do
  cp "$out/fast.bake.good" "$cache/$fast_key.bake"
  damage "$mode" "$cache/$fast_key.bake"
  cmp -s "$out/fast.bake.good" "$cache/$fast_key.bake" && fail "$mode: the damage changed nothing"
  rm -f "$cache/$fast_key.corrupt"
  start
  bake "$fast"
  [ "$(json_field "$job" cache_hit)" = false ] || fail "$mode .bake was taken for the product: $job"
  [ "$key" = "$fast_key" ] || fail "$mode: the key changed: $key, was $fast_key"
  corrupt=$(metric "$port" 'scatter_bake_cache_lookups_total{result="corrupt"}')
  [ "$corrupt" = 1 ] || fail "$mode .bake: scatter_bake_cache_lookups_total{result=\"corrupt\"} is $corrupt, expected 1"
  [ -e "$cache/$fast_key.corrupt" ] || fail "$mode .bake was not moved aside to $fast_key.corrupt"
  grep -q "event=bake_cache_corrupt" "${daemon_log[d]}" || fail "$mode: no bake_cache_corrupt line in the log"
  render "$fast" "$out/fast-$mode.png"
  expect_from_cache "$mode: render after the re-bake"
  cmp -s "$out/reference.png" "$out/fast-$mode.png" || fail "$mode: the re-baked image differs from the reference"
  stop_daemon d
  echo "ok: $mode .bake detected, moved aside, re-baked; the same image"
done
