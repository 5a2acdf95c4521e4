#!/usr/bin/env bash
# Usage: nginx.sh SCATTERD SOURCE_DIR OUT_DIR
# Debian's nginx on loopback, configured from docker/nginx.conf.in (as docker/ ships it), in front
# of two scatterd daemons that share one cache directory (as in docker/compose.yaml). Shows:
#  (a) requests and live sessions with different routing keys spread over both daemons, and one
#      key always reaches the same daemon;
#  (b) a bake made through one daemon is a disk-cache hit through the other;
#  (c) promtool (Debian's prometheus package) accepts both daemons' /metrics;
#  (d) with one daemon killed, new requests and sessions of its keys go to the other.
set -euo pipefail
scatterd=$1 src=$2 out=$3
rm -rf "$out" && mkdir -p "$out"
# shellcheck source=tests/cli/daemon_lib.sh
source "$src/tests/cli/daemon_lib.sh"
for tool in nginx promtool curl; do
  command -v "$tool" >/dev/null || [ -x "/usr/sbin/$tool" ] ||
    fail "$tool is not installed (scripts/setup installs scripts/packages.txt)"
done
nginx_bin=$(command -v nginx || echo /usr/sbin/nginx)
nginx_pid=""
# nginx's workers outlive a master killed with -9: TERM it (it stops them), then make sure.
stop_nginx() {
  [ -n "$nginx_pid" ] || return 0
  local workers
  workers=$(cat "/proc/$nginx_pid/task/$nginx_pid/children" 2>/dev/null || true)
  kill -TERM "$nginx_pid" 2>/dev/null || true
  for _ in $(seq 50); do kill -0 "$nginx_pid" 2>/dev/null || break; sleep 0.1; done
  # shellcheck disable=SC2086
  kill -9 "$nginx_pid" $workers 2>/dev/null || true
  { wait "$nginx_pid"; } 2>/dev/null || true
  nginx_pid=""
}
cleanup() {
  stop_nginx
  stop_all
}
trap cleanup EXIT

# ---- the shipped configuration is the template's rendering --------------------------------
"$src/docker/render-nginx-conf" --compose | diff -u "$src/docker/nginx.conf" - >"$out/compose.diff" ||
  fail "docker/nginx.conf is not docker/render-nginx-conf --compose's output: $(cat "$out/compose.diff")"

# ---- two daemons, one cache ----------------------------------------------------------------
for d in a b; do
  start_daemon "$d" "$scatterd" --scenes-dir "$src/scenes" --cache-dir "$out/cache"
done
declare -A name_of=(["127.0.0.1:${daemon_port[a]}"]=a ["127.0.0.1:${daemon_port[b]}"]=b)

# ---- nginx: the rendered template inside a main context of the test's own -----------------
# nginx has no "any free port": try a few random ones.
mkdir -p "$out/nginx/logs" "$out/nginx/tmp"
start_nginx() {
  "$src/docker/render-nginx-conf" --listen "127.0.0.1:$proxy" \
    --server "127.0.0.1:${daemon_port[a]}" --server "127.0.0.1:${daemon_port[b]}" \
    >"$out/nginx/scatter.conf"
  cat >"$out/nginx/nginx.conf" <<EOF
$([ "$(id -u)" -ne 0 ] || echo "user root;")
worker_processes 1;
pid $out/nginx/nginx.pid;
error_log $out/nginx/logs/error.log info;
events { worker_connections 256; }
http {
  access_log $out/nginx/logs/access.log;
  client_body_temp_path $out/nginx/tmp/body;
  proxy_temp_path $out/nginx/tmp/proxy;
  fastcgi_temp_path $out/nginx/tmp/fastcgi;
  uwsgi_temp_path $out/nginx/tmp/uwsgi;
  scgi_temp_path $out/nginx/tmp/scgi;
  # For this test only: which daemon answered.
  add_header X-Upstream \$upstream_addr always;
  include $out/nginx/scatter.conf;
}
EOF
  "$nginx_bin" -p "$out/nginx" -c "$out/nginx/nginx.conf" -e "$out/nginx/logs/error.log" \
    -g 'daemon off;' >>"$out/nginx/logs/stdout.log" 2>&1 &
  nginx_pid=$!
  local deadline=$((SECONDS + 10))
  while [ $SECONDS -lt $deadline ]; do
    kill -0 "$nginx_pid" 2>/dev/null || return 1  # the port was taken (or the config is bad)
    curl -s -o /dev/null "http://127.0.0.1:$proxy/api/health" && return 0
    sleep 0.1
  done
  fail "nginx did not answer within 10 s: $(tail -5 "$out/nginx/logs/error.log")"
}
for try in 1 2 3 4 5 6; do
  proxy=$((20000 + RANDOM % 30000))
  start_nginx && break
  stop_nginx
  [ $try -lt 6 ] || fail "nginx would not start: $(tail -5 "$out/nginx/logs/error.log")"
done
echo "nginx on 127.0.0.1:$proxy in front of a (${daemon_port[a]}) and b (${daemon_port[b]})"

# via KEY METHOD PATH [BODY] [CURL ARGS...]: a request through nginx with routing key KEY (sent
# as the X-Scatter-Route header); sets status, reply and `served` (a or b).
via() {
  local key=$1
  shift
  api "$proxy" "$1" "$2" "${3-}" -D "$out/via.headers" -H "X-Scatter-Route: $key" "${@:4}"
  served=$(upstream_of "$out/via.headers")
}
# upstream_of HEADERS: the daemon (a or b) that answered; nginx lists every one it tried, as
# "addr, addr", the last one answered.
upstream_of() {
  local up
  up=$(sed -n 's/^X-Upstream: *//Ip' "$1" | tr -d '\r' | tail -1)
  tried=$up
  echo "${name_of[${up##* }]:-none ($up)}"
}
requests_on() { metric "${daemon_port[$1]}" "scatter_http_requests_total{route=\"$2\",status=\"$3\"}"; }

# ---- (a) keys spread, and stick -------------------------------------------------------------
keys=(sphere bunny layers cube-torus)
for i in $(seq 1 28); do keys+=("$(printf '%064x' "$((i * 7919))")"); done  # like asset ids
declare -A home=()
count_a=0 count_b=0
for key in "${keys[@]}"; do
  for _ in 1 2 3; do
    via "$key" GET /api/health
    [ "$status" = 200 ] || fail "GET /api/health via nginx (key $key): status $status: $reply"
    [ "${home[$key]:-$served}" = "$served" ] || fail "key $key went to ${home[$key]}, then to $served"
    home[$key]=$served
  done
  [ "$served" = a ] && count_a=$((count_a + 3)) || count_b=$((count_b + 3))
done
on_a=$(requests_on a /api/health 200) on_b=$(requests_on b /api/health 200)
# The daemons' own counts, not nginx's word; nginx's own readiness probes add a few to one of them.
[ "$on_a" -ge "$count_a" ] && [ "$on_b" -ge "$count_b" ] && [ $((on_a + on_b)) -le $((count_a + count_b + 60)) ] ||
  fail "the daemons counted $on_a and $on_b health requests; nginx said $count_a and $count_b"
[ "$count_a" -gt 0 ] && [ "$count_b" -gt 0 ] ||
  fail "${#keys[@]} routing keys all went to one daemon (a: $count_a, b: $count_b requests)"
# The query parameter (what a browser's WebSocket sends) routes like the header.
for key in "${keys[@]:0:6}"; do
  api "$proxy" GET "/api/health?route=$key" "" -D "$out/via.headers"
  up=$(upstream_of "$out/via.headers")
  [ "$up" = "${home[$key]}" ] || fail "?route=$key went to $up, the header to ${home[$key]}"
done
echo "ok: ${#keys[@]} keys: $count_a requests on a, $count_b on b; each key on one daemon"

# Live sessions: WebSocket upgrades through nginx, held open, one per key: 8 keys of each daemon
# (within the daemons' 16 sessions).
ws_open() {  # ws_open KEY: opens fd ws_fd[KEY], checks the 101
  local fd line
  exec {fd}<>"/dev/tcp/127.0.0.1/$proxy"
  printf 'GET /api/ws?route=%s HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n' "$1" >&"$fd"
  IFS= read -r -t 10 line <&"$fd" || fail "WebSocket upgrade via nginx (key $1): no answer"
  [[ $line == "HTTP/1.1 101"* ]] || fail "WebSocket upgrade via nginx (key $1): $line"
  while IFS= read -r -t 10 line <&"$fd" && [ "${line%$'\r'}" != "" ]; do :; done
  ws_fd[$1]=$fd
}
ws_send() {  # ws_send KEY TEXT: one masked text frame (a zero mask: the bytes go as they are)
  local n=${#2}
  if [ "$n" -lt 126 ]; then
    printf "\\x81\\x$(printf %02x $((128 + n)))\\x00\\x00\\x00\\x00%s" "$2" >&"${ws_fd[$1]}"
  else
    printf "\\x81\\xfe\\x$(printf %02x $((n >> 8)))\\x$(printf %02x $((n & 255)))\\x00\\x00\\x00\\x00%s" "$2" >&"${ws_fd[$1]}"
  fi
}
declare -A ws_fd=()
session_keys=()
for d in a b; do
  n=0
  for key in "${keys[@]}"; do
    [ "${home[$key]}" = "$d" ] && [ $n -lt 8 ] && session_keys+=("$key") && n=$((n + 1))
  done
done
for key in "${session_keys[@]}"; do ws_open "$key"; done
sessions_a=$(metric "${daemon_port[a]}" scatter_sessions) sessions_b=$(metric "${daemon_port[b]}" scatter_sessions)
expect_a=0
for key in "${session_keys[@]}"; do [ "${home[$key]}" != a ] || expect_a=$((expect_a + 1)); done
expect_b=$((${#session_keys[@]} - expect_a))
[ "$sessions_a" = "$expect_a" ] && [ "$sessions_b" = "$expect_b" ] ||
  fail "${#session_keys[@]} sessions: a holds $sessions_a and b $sessions_b, their keys say $expect_a and $expect_b"
[ "$sessions_a" -gt 0 ] && [ "$sessions_b" -gt 0 ] || fail "the sessions are all on one daemon ($sessions_a, $sessions_b)"
# A frame comes back through the proxy.
small='{"mesh": {"shape": "sphere", "radius": 1}, "medium": {"sigma_s": [2, 2, 2], "sigma_a": [0.05, 0.05, 0.05],
  "density": {"type": "constant"}}, "lights": [{"type": "point", "position": [3, 3, 3], "color": [1, 1, 1], "intensity": 20}],
  "camera": {"position": [0, 0, 4], "target": [0, 0, 0], "up": [0, 1, 0], "fov_deg": 40},
  "image": {"width": 32, "height": 32}, "voxels": 16}'
ws_send "${session_keys[0]}" "{\"type\": \"hello\", \"scene\": $small, \"pipeline\": \"surface\", \"format\": \"png\"}"
frame=""
IFS= read -r -t 30 -d '}' frame <&"${ws_fd[${session_keys[0]}]}" || true
grep -qE '"frame":[0-9]+' <<<"$frame" || fail "no frame through nginx within 30 s: ${frame:0:300}"
for fd in "${ws_fd[@]}"; do exec {fd}>&-; done
echo "ok: ${#session_keys[@]} sessions: $sessions_a on a, $sessions_b on b; a frame came back through nginx"

# ---- (b) a bake through one daemon is a cache hit through the other ------------------------
for key in "${keys[@]}"; do [ "${home[$key]}" = a ] && key_a=$key; [ "${home[$key]}" = b ] && key_b=$key; done
bake_body="{\"scene\": $small, \"pipeline\": \"single\", \"settings\": {\"samples\": 500, \"directions\": 16, \"sh_order\": 3}}"
# bake_via KEY: posts the bake through nginx and follows it there (same key: same daemon).
bake_via() {
  via "$1" POST /api/bakes "$bake_body"
  [[ $status == 20[02] ]] || fail "POST /api/bakes via nginx (key $1): status $status: $reply"
  local id deadline=$((SECONDS + 60))
  id=$(json_field "$reply" id)
  while [ "$(json_field "$reply" state)" != done ]; do
    [[ $(json_field "$reply" state) =~ ^(queued|running)$ ]] || fail "bake via key $1: $reply"
    [ $SECONDS -lt $deadline ] || fail "bake via key $1 not done in 60 s: $reply"
    sleep 0.2
    via "$1" GET "/api/bakes/$id"
    [ "$status" = 200 ] || fail "GET /api/bakes/$id via nginx (key $1, on $served): status $status: $reply"
  done
}
bake_via "$key_a"
[ "$served" = a ] && [ "$(json_field "$reply" cache_hit)" = false ] || fail "first bake (on $served): $reply"
bake_key=$(json_field "$reply" key)
bake_via "$key_b"
[ "$served" = b ] && [ "$(json_field "$reply" cache_hit)" = true ] ||
  fail "the same bake through b (on $served) was not a cache hit: $reply"
[ "$(json_field "$reply" key)" = "$bake_key" ] || fail "the key differs between the daemons: $reply"
hits_b=$(metric "${daemon_port[b]}" 'scatter_bake_cache_lookups_total{result="disk_hit"}')
[ "$hits_b" = 1 ] || fail "b's disk hits: $hits_b, expected 1"
echo "ok: baked on a ($bake_key), a disk hit on b"
# An upload through one daemon (keyed by ?route=, which the daemon ignores) renders through the other.
tetra=$'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n'
api "$proxy" POST "/api/assets?route=$key_a&kind=mesh&format=obj" "$tetra" -D "$out/via.headers"
[ "$status" = 201 ] && [ "$(upstream_of "$out/via.headers")" = a ] ||
  fail "upload via a: status $status on $(upstream_of "$out/via.headers"): $reply"
asset=$(json_field "$reply" id)
via "$key_b" POST /api/render "{\"scene\": ${small/\"shape\": \"sphere\", \"radius\": 1/\"asset\": \"$asset\", \"fit\": 2}, \"pipeline\": \"surface\", \"format\": \"json\"}"
[ "$status" = 200 ] && [ "$served" = b ] || fail "render of a's upload via b (on $served): status $status: $reply"
echo "ok: mesh $asset uploaded through a, rendered through b"

# ---- (c) promtool accepts the daemons' metrics ---------------------------------------------
for d in a b; do
  curl -sS "http://127.0.0.1:${daemon_port[$d]}/metrics" >"$out/metrics.$d"
  promtool check metrics <"$out/metrics.$d" >"$out/promtool.$d" 2>&1 ||
    fail "promtool check metrics rejects daemon $d's /metrics: $(cat "$out/promtool.$d")"
done
echo "ok: promtool accepts /metrics ($(wc -l <"$out/metrics.a") and $(wc -l <"$out/metrics.b") lines)"

# ---- (d) one daemon killed: its keys go to the other ---------------------------------------
before_b=$(requests_on b /api/health 200)
stop_daemon a KILL
moved=0
for key in "${keys[@]}"; do
  via "$key" GET /api/health
  [ "$status" = 200 ] || fail "with a killed, GET /api/health (key $key): status $status: $reply"
  [ "$served" = b ] || fail "with a killed, key $key was served by $served"
  [ "${home[$key]}" = b ] || moved=$((moved + 1))
done
after_b=$(requests_on b /api/health 200)
[ $((after_b - before_b)) -ge ${#keys[@]} ] || fail "b counted $((after_b - before_b)) of ${#keys[@]} requests"
ws_fd=()
ws_open "$key_a"
[ "$(metric "${daemon_port[b]}" scatter_sessions)" -ge 1 ] || fail "a session of a's key did not open on b"
fd=${ws_fd[$key_a]}
exec {fd}>&-
echo "ok: a killed: all ${#keys[@]} keys ($moved of them a's) and a new session served by b"
