#!/usr/bin/env bash
# Live sessions while a bake runs (issue 17, item 4): 4 scatter-load sessions on sphere/surface,
# first alone, then while a 50k-sample `single` bake of layers runs on the bake thread. Prints
# both reports' pose-to-frame percentiles and fps, and the bake's state during the second run.
# Usage: bench/bake-sessions.sh [--scatterd PATH] [--duration S] [--samples N]
set -euo pipefail
cd "$(dirname "$0")/.."
scatterd=build/scatterd duration=20 samples=50000
while [ $# -gt 0 ]; do
  case $1 in
    --scatterd) scatterd=$2; shift 2 ;;
    --duration) duration=$2; shift 2 ;;
    --samples) samples=$2; shift 2 ;;
    *) echo "usage: $0 [--scatterd PATH] [--duration S] [--samples N]" >&2; exit 2 ;;
  esac
done
out=bench/out/bake-sessions
rm -rf "$out" && mkdir -p "$out"
source scripts/start_scatterd.sh
start_scatterd "$scatterd" "$out/serve.log" --scenes-dir scenes --cache-dir "$out/cache"
port=$scatterd_port
load=(build/scatter-load live --port "$port" --sessions 4 --scene sphere --pipeline surface --duration "$duration")
summary() {  # REPORT: pose-to-frame p50/p95/p99 and fps
  node -e 'const r = JSON.parse(require("fs").readFileSync(process.argv[1]));
    const p = r.pose_to_frame_ms; console.log(`pose-to-frame p50 ${p.p50.toFixed(0)} / p95 ${p.p95.toFixed(0)} / p99 ${p.p99.toFixed(0)} ms, ` +
    `${(r.fps_total / r.sessions_admitted).toFixed(1)} fps per session, fairness ${r.fairness.min_over_max.toFixed(2)}`)' "$1"
}
"${load[@]}" >"$out/alone.json"
echo "4 sessions alone:        $(summary "$out/alone.json")"
bake=$(curl -s -d "{\"scene_name\": \"layers\", \"pipeline\": \"single\", \"settings\": {\"samples\": $samples}}" \
  "http://127.0.0.1:$port/api/bakes")
id=$(node -e 'console.log(JSON.parse(process.argv[1]).id)' "$bake")
start=$(date +%s)
"${load[@]}" >"$out/bake.json"
state=$(curl -s "http://127.0.0.1:$port/api/bakes/$id")
echo "4 sessions during a bake: $(summary "$out/bake.json")"
echo "the bake after the run ($(( $(date +%s) - start )) s): $(node -e 'const s = JSON.parse(process.argv[1]); console.log(`${s.state}, ${s.stage}, progress ${s.progress.toFixed(2)}`)' "$state")"
until node -e 'process.exit(["done","failed","cancelled"].includes(JSON.parse(process.argv[1]).state) ? 0 : 1)' \
      "$(curl -s "http://127.0.0.1:$port/api/bakes/$id")"; do sleep 1; done
echo "bake finished after $(( $(date +%s) - start )) s: $(curl -s "http://127.0.0.1:$port/api/bakes/$id" | node -e 'let d="";process.stdin.on("data",c=>d+=c).on("end",()=>{const s=JSON.parse(d);console.log(s.state, "seconds", s.seconds.toFixed(1))})')"
