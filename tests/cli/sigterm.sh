#!/usr/bin/env bash
# SIGTERM with renders queued and one in flight: the daemon exits within 2 s, with status 0, and
# the waiting clients are told (503) rather than left hanging.
# Usage: sigterm.sh SCATTERD SOURCE_DIR OUT_DIR
set -euo pipefail
bin=$1 src=$2 out=$3
rm -rf "$out" && mkdir -p "$out"
source "$src/tests/cli/daemon_lib.sh"
trap stop_all EXIT

start_daemon a "$bin" --scenes-dir "$src/scenes" --cache-dir none --max-render-s 100000
port=${daemon_port[a]}
long='{"scene_name": "sphere", "pipeline": "reference", "terms": "all", "format": "json", "settings": {"spp": 100000}}'
for i in 1 2 3 4; do
  curl -s -o "$out/render$i.json" -w '%{http_code}' --data-binary "$long" "http://127.0.0.1:$port/api/render" \
    >"$out/status$i" 2>/dev/null &
done
deadline=$((SECONDS + 60))
until api "$port" GET /api/health && [ "$(json_field "$reply" render_busy)" = true ]; do
  [ $SECONDS -lt $deadline ] || fail "the render never started: $reply"
  sleep 0.1
done
api "$port" GET /api/health
depth=$(json_field "$reply" queue_depth)
[ "$depth" -ge 1 ] || fail "expected renders queued behind the running one, queue_depth $depth"

start=$(date +%s.%N)
stop_daemon a TERM
took=$(echo "$(date +%s.%N) - $start" | bc)
echo "exit after SIGTERM: $took s with 1 render running and $depth queued"
(( $(echo "$took < 2" | bc) )) || fail "SIGTERM took $took s (limit 2 s)"
wait
for i in 1 2 3 4; do
  s=$(cat "$out/status$i")
  [ "$s" = 503 ] || [ "$s" = 000 ] || fail "render $i answered $s: $(cat "$out/render$i.json")"
done
grep -q "render not run: the server is stopping\|render cancelled: the server is stopping" "$out"/render*.json ||
  fail "no client was told the server is stopping"
echo "OK"
