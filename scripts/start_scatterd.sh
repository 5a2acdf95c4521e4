# Sourced (not run) by bench/load.sh and tests/cli/load_smoke.sh:
#   start_scatterd SCATTERD LOG [serve options...]
# starts `SCATTERD serve --port 0 ...` in the background (a free loopback port), waits for its
# "serving on" line and sets scatterd_pid and scatterd_port; the daemon is stopped on exit.
start_scatterd() {
  local bin=$1 log=$2
  shift 2
  "$bin" serve --port 0 "$@" >"$log" 2>&1 &
  scatterd_pid=$!
  trap 'kill $scatterd_pid 2>/dev/null || true; wait $scatterd_pid 2>/dev/null || true' EXIT
  scatterd_port=
  for _ in $(seq 150); do
    scatterd_port=$(grep -oE 'serving on http://[^/]+/' "$log" | grep -oE '[0-9]+/$' | tr -d / || true)
    [ -n "$scatterd_port" ] && return 0
    kill -0 "$scatterd_pid" 2>/dev/null || break
    sleep 0.2
  done
  echo "scatterd did not start:" >&2
  cat "$log" >&2
  return 1
}
