#!/usr/bin/env bash
# The service under load, for docs/BENCHMARKS.md: scatter-load against a daemon this script starts
# on a free loopback port (its own cache folder under bench/out/load/).
#   - live sessions: 1, 4 and 16 concurrent on bunny/surface, sphere/thickness and layers/single
#     (each --duration seconds, orbit at 30 Hz; layers/single is baked first, through REST);
#   - 17 sessions against --max-sessions 16: the 17th is refused (503) and counted;
#   - REST: 4 clients rendering sphere/surface as JPEG;
#   - with --soak: 16 sessions for --soak-s seconds (600) on bunny/surface, RSS every 5 s.
# Usage: bench/load.sh [--scatterd PATH] [--duration S] [--soak] [--soak-s S] [--only soak]
# Reports: bench/out/load/*.json; a table of them: node bench/load-table.mjs bench/out/load/*.json
set -euo pipefail
cd "$(dirname "$0")/.."
scatterd=build/scatterd load=build/scatter-load duration=30 soak=0 soak_s=600 only=
while [ $# -gt 0 ]; do
  case $1 in
    --scatterd) scatterd=$2; shift 2 ;;
    --duration) duration=$2; shift 2 ;;
    --soak) soak=1; shift ;;
    --soak-s) soak_s=$2; shift 2 ;;
    --only) only=$2; shift 2 ;;
    *) echo "bench/load.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
out=bench/out/load
mkdir -p "$out"
source scripts/start_scatterd.sh
start_scatterd "$scatterd" "$out/serve.log" --scenes-dir scenes --cache-dir "$out/cache"
port=$scatterd_port pid=$scatterd_pid
echo "scatterd $scatterd (pid $pid) on port $port; reports in $out" >&2
# --pid: RSS from /proc for a daemon whose /metrics predates process_resident_memory_bytes.
common=(--port "$port" --pid "$pid")
# Before each run: wait until the last run's sessions have given their slots back and the render
# queue is empty (a closed session's queued frame still renders first), so that each run starts
# from an idle daemon; says how long that took.
wait_idle() {
  node -e '
    const url = process.argv[1], t0 = Date.now();
    const idle = (m) => /^scatter_sessions 0$/m.test(m) && /^scatter_render_queue_depth 0$/m.test(m);
    (async () => {
      for (;;) {
        if (idle(await (await fetch(url)).text())) break;
        if (Date.now() - t0 > 300000) { console.error("  daemon still busy after 300 s"); process.exit(1); }
        await new Promise((r) => setTimeout(r, 100));
      }
      console.error(`  idle after ${((Date.now() - t0) / 1000).toFixed(1)} s`);
    })();' "http://127.0.0.1:$port/metrics"
}

if [ -z "$only" ]; then
  "$load" rest "${common[@]}" --scene layers --pipeline single --ops bake --cycles 1 >"$out/bake-layers-single.json"
  for case in bunny/surface sphere/thickness layers/single; do
    scene=${case%/*} pipeline=${case#*/}
    for n in 1 4 16; do
      wait_idle
      echo "live $scene/$pipeline, $n sessions, ${duration} s" >&2
      "$load" live "${common[@]}" --scene "$scene" --pipeline "$pipeline" --sessions "$n" \
        --duration "$duration" >"$out/live-$scene-$pipeline-$n.json"
    done
  done
  wait_idle
  echo "17 sessions (--max-sessions 16)" >&2
  "$load" live "${common[@]}" --scene bunny --pipeline surface --sessions 17 --duration 10 >"$out/live-refusal-17.json"
  wait_idle
  echo "rest: 4 clients rendering sphere/surface" >&2
  "$load" rest "${common[@]}" --scene sphere --pipeline surface --format jpg --clients 4 \
    --duration "$duration" >"$out/rest-sphere-surface-4.json"
fi
if [ "$soak" = 1 ] || [ "$only" = soak ]; then
  wait_idle
  echo "soak: 16 sessions on bunny/surface for $soak_s s" >&2
  "$load" live "${common[@]}" --scene bunny --pipeline surface --sessions 16 --duration "$soak_s" \
    --rss-interval 5 >"$out/soak-bunny-surface-16.json"
fi
node bench/load-table.mjs "$out"/*.json
