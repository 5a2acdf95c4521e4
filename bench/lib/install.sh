# Sourced by the bench scripts. bench_install PACKAGE...: installs the Debian packages that are
# missing, once (benchmark dependencies such as blender or Python's numpy and OpenImageIO for
# /usr/bin/python3; never the project's own, which scripts/setup installs).
bench_install() {
  local need=() p sudo=""
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need+=("$p")
  done
  [ ${#need[@]} -eq 0 ] && return 0
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  echo "bench: installing ${need[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq "${need[@]}" >/dev/null
}
