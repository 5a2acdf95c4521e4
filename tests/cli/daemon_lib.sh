# Helpers for tests that drive scatterd daemons over loopback (sourced, not run).
# A test sets `out` (its scratch folder) before calling them; every daemon started here is killed
# by stop_all, which the test puts in its EXIT trap.

declare -A daemon_pid=() daemon_port=() daemon_log=()
starts=0

fail() { echo "FAIL: $*" >&2; exit 1; }

# start_daemon NAME SCATTERD ARGS...: serves on a free loopback port; sets daemon_port[NAME] and
# daemon_log[NAME] (its output: the "serving on" line, then the log, one file per start).
start_daemon() {
  local name=$1 bin=$2
  shift 2
  starts=$((starts + 1))
  local log=$out/$name.$starts.log
  daemon_log[$name]=$log
  "$bin" serve --bind 127.0.0.1 --port 0 --log-level info "$@" >"$log" 2>&1 &
  daemon_pid[$name]=$!
  local deadline=$((SECONDS + 30)) port=""
  while [ -z "$port" ]; do
    port=$(grep -oE 'serving on http://127\.0\.0\.1:[0-9]+/' "$log" 2>/dev/null | grep -oE '[0-9]+/$' | tr -d /) || true
    kill -0 "${daemon_pid[$name]}" 2>/dev/null || fail "daemon $name exited at start: $(tail -5 "$log")"
    [ $SECONDS -lt $deadline ] || fail "daemon $name did not say it was serving within 30 s"
    [ -n "$port" ] || sleep 0.1
  done
  daemon_port[$name]=$port
}

# stop_daemon NAME [SIGNAL]: TERM (default) must end it with status 0; KILL ends it at once.
stop_daemon() {
  local name=$1 sig=${2:-TERM} pid=${daemon_pid[$1]} rc=0
  kill -"$sig" "$pid"
  { wait "$pid"; } 2>/dev/null || rc=$?  # (bash would report "Killed")
  unset "daemon_pid[$name]"
  if [ "$sig" = TERM ] && [ $rc -ne 0 ]; then fail "daemon $name exited with status $rc on SIGTERM"; fi
  return 0
}

stop_all() {
  local name
  for name in "${!daemon_pid[@]}"; do kill -9 "${daemon_pid[$name]}" 2>/dev/null || true; done
  wait 2>/dev/null || true
}

# api PORT METHOD PATH [BODY] [CURL ARGS...]: sets `status` (the HTTP status) and `reply` (the
# body, unless it is an image: then `reply` is empty and the body is in $out/reply).
api() {
  local port=$1 method=$2 path=$3 body=${4-}
  shift $(($# < 4 ? $# : 4))
  local file=$out/reply
  status=$(curl -sS -o "$file" -w '%{http_code}' -X "$method" ${body:+--data-binary "$body"} "$@" \
           "http://127.0.0.1:$port$path") || fail "$method $path: curl failed"
  reply=""
  if [ "$(head -c 4 "$file" | od -An -c | tr -d ' ')" != '211PNG' ]; then reply=$(cat "$file"); fi
}

# json_field JSON NAME: the first scalar value of "NAME" (strings without their quotes).
json_field() {
  grep -oE "\"$2\":(\"[^\"]*\"|[^,}]*)" <<<"$1" | head -1 | cut -d: -f2- | tr -d '"'
}

# metric PORT SERIES: the value of one sample line of /metrics, e.g.
# 'scatter_bake_cache_lookups_total{result="corrupt"}' (0 when absent).
metric() {
  api "$1" GET /metrics
  [ "$status" = 200 ] || fail "GET /metrics: status $status"
  local v
  v=$(awk -v series="$2" '$1 == series { print $2 }' <<<"$reply")
  echo "${v:-0}"
}

# wait_bake PORT ID [SECONDS]: polls the job until it finishes; sets `reply` to its status.
wait_bake() {
  local deadline=$((SECONDS + ${3:-60}))
  while :; do
    api "$1" GET "/api/bakes/$2"
    [ "$status" = 200 ] || fail "GET /api/bakes/$2: status $status: $reply"
    case $(json_field "$reply" state) in
      done) return 0 ;;
      failed | cancelled) fail "bake $2 ended $(json_field "$reply" state): $reply" ;;
    esac
    [ $SECONDS -lt $deadline ] || fail "bake $2 not done within ${3:-60} s: $reply"
    sleep 0.2
  done
}
