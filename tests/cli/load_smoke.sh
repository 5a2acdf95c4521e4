#!/usr/bin/env bash
# Usage: load_smoke.sh SCATTERD SCATTER_LOAD SOURCE_DIR OUT_DIR
# scatter-load against a daemon on a free loopback port (--max-sessions 2): two live sessions on
# sphere/surface get frames, pose-to-frame figures and no errors, and the report carries the
# daemon's RSS from /metrics; three sessions: the third is refused with 503, counted, exit 0; a
# session whose every frame fails ends at --frames with the failures counted. A bad
# option and an unreachable daemon are clear errors with a non-zero exit.
set -eu
scatterd=$1 load=$2 src=$3 out=$4
rm -rf "$out" && mkdir -p "$out"
source "$src/scripts/start_scatterd.sh"
start_scatterd "$scatterd" "$out/serve.log" --max-sessions 2 --cache-dir none --scenes-dir "$src/scenes"
port=$scatterd_port pid=$scatterd_pid

"$load" live --port "$port" --sessions 2 --scene sphere --pipeline surface --duration 5 \
  --rss-interval 0.5 --light-every 10 >"$out/two.json"
sleep 1  # the two sessions' slots are given back as their connections close
"$load" live --port "$port" --sessions 3 --duration 2 >"$out/three.json"
# Every frame fails (thickness needs a homogeneous medium; the bunny's is noise): a run bounded
# by --frames alone still ends, the failures counted as answers.
timeout 120 "$load" live --port "$port" --scene bunny --pipeline thickness --duration 0 --frames 2 \
  >"$out/failing.json"
node "$src/tests/cli/load_smoke_check.mjs" "$out/two.json" "$out/three.json" "$out/failing.json"

if "$load" live --port "$port" --path spiral 2>"$out/bad.err"; then
  echo "FAIL: --path spiral was accepted"; exit 1
fi
grep -q "spiral" "$out/bad.err" || { echo "FAIL: the error does not name the value:"; cat "$out/bad.err"; exit 1; }
kill $pid && wait $pid 2>/dev/null || true
if "$load" live --port "$port" --duration 1 2>"$out/gone.err" >/dev/null; then
  echo "FAIL: a run against no daemon exited 0"; exit 1
fi
grep -q "cannot reach scatterd at 127.0.0.1:$port" "$out/gone.err" || { echo "FAIL:"; cat "$out/gone.err"; exit 1; }
echo "ok"
