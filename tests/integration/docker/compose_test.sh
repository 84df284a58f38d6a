#!/usr/bin/env bash
# The compose rig for real (docs/docker.md): a Docker engine (the machine's, or dockerd started
# here and stopped after, the machine's firewall and forwarding left as they were found), base
# images made locally when absent, the image built, the default scenario run under
# docker-compose plain and with CURVE by the documented command, the report and plots checked,
# a folder the rig cannot write refused on screen, and nothing left behind by `down`.
#
#   compose_test.sh SOURCE_DIR
#
# Exit 0 on success, 1 on a failure (the line says which check), 77 when it cannot run here (no
# engine answers and this is not root, so none can be started): ctest counts that as skipped.
set -euo pipefail
src=$(cd "${1:?usage: compose_test.sh SOURCE_DIR}" && pwd)
cd "$src"

work=$(mktemp -d /var/tmp/compose-test.XXXXXX)
project=tactile-test-$$
started_engine=0
say() { echo "compose_test: $*" >&2; }
fail() { say "FAILED: $*"; exit 1; }

# --- The engine -----------------------------------------------------------------------------
saved_rules=""
restore_machine() {
  # Docker's rules, the FORWARD policy it set and the forwarding it switched on go; the ruleset
  # found at the start comes back exactly.
  if command -v nft >/dev/null 2>&1 && [ -n "$saved_rules" ]; then
    nft flush ruleset
    nft -f "$saved_rules"
  fi
  local s
  for s in net.ipv4.ip_forward net.ipv6.conf.all.forwarding; do
    [ -n "${saved_sysctl[$s]:-}" ] && sysctl -qw "$s=${saved_sysctl[$s]}" || true
  done
  if [ "$had_docker0" = 0 ] && ip link show docker0 >/dev/null 2>&1; then ip link delete docker0; fi
}
declare -A saved_sysctl=()
had_docker0=1
stop_engine() {
  [ "$started_engine" = 1 ] || return 0
  local pid
  pid=$(cat "$work/dockerd.pid" 2>/dev/null || true)
  if [ -n "$pid" ] && kill "$pid" 2>/dev/null; then
    for _ in $(seq 1 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
    kill -0 "$pid" 2>/dev/null && kill -9 "$pid" 2>/dev/null || true
  fi
  restore_machine
  started_engine=0
}
cleanup() {
  local status=$?
  if [ -n "${compose_cmd:-}" ]; then
    "${compose_cmd[@]}" -p "$project" -f docker/compose.yaml -f docker/compose.curve.yaml \
      down --volumes --remove-orphans >/dev/null 2>&1 || true
  fi
  stop_engine
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT

if docker info >/dev/null 2>&1; then
  say "using the Docker engine that answers here ($(docker info -f '{{.ServerVersion}}'))"
else
  if [ "$(id -u)" != 0 ]; then
    say "no Docker engine answers and starting one needs root: cannot run here"
    exit 77
  fi
  command -v dockerd >/dev/null 2>&1 || fail "dockerd is missing (bash scripts/install-deps --test installs docker.io)"
  if command -v nft >/dev/null 2>&1; then
    saved_rules=$work/ruleset.nft
    nft list ruleset >"$saved_rules"
  fi
  for s in net.ipv4.ip_forward net.ipv6.conf.all.forwarding; do
    saved_sysctl[$s]=$(sysctl -n "$s" 2>/dev/null || true)
  done
  ip link show docker0 >/dev/null 2>&1 || had_docker0=0
  say "starting dockerd (log: $work/dockerd.log)"
  started_engine=1
  dockerd --data-root /var/lib/docker --pidfile "$work/dockerd.pid" >"$work/dockerd.log" 2>&1 &
  for _ in $(seq 1 150); do docker info >/dev/null 2>&1 && break; sleep 0.2; done
  docker info >/dev/null 2>&1 || { tail -n 20 "$work/dockerd.log" >&2; fail "dockerd did not answer within 30 s"; }
fi
if command -v docker-compose >/dev/null 2>&1; then
  compose_cmd=(docker-compose)
else
  compose_cmd=(docker compose)
fi
"${compose_cmd[@]}" version >/dev/null 2>&1 || fail "no docker-compose and no 'docker compose'"

bash scripts/docker-base-images

# --- Checks -----------------------------------------------------------------------------------
json_value() {  # json_value FILE KEY: the value of a top-level scalar key, as printed
  sed -n "s/.*\"$2\":[[:space:]]*\([^,}]*\).*/\1/p" "$1" | head -n 1 | tr -d ' "'
}
check_report() {  # check_report DIR
  local dir=$1 report=$1/report.json
  [ -s "$report" ] || fail "$report is missing"
  [ "$(json_value "$report" completed)" = true ] || fail "$report: completed is not true"
  [ "$(json_value "$report" dropped)" = false ] || fail "$report: the cap was dropped"
  local tight true_tight
  tight=$(json_value "$report" tightened_cycle)
  true_tight=$(json_value "$report" true_tight_cycle)
  [[ "$tight" =~ ^[0-9]+$ && "$true_tight" =~ ^[0-9]+$ ]] || fail "$report: no tight cycle ($tight, true $true_tight)"
  # The paper's rule (two consecutive slipping cycles) may declare it one cycle late, never early.
  [ "$tight" -ge "$true_tight" ] && [ "$tight" -le $((true_tight + 1)) ] ||
    fail "$report: tight in cycle $tight, truly in cycle $true_tight"
  [ "$(stat -c %u "$report")" = "$(id -u)" ] || fail "$report is not owned by the invoking user"
  local png
  for png in fig10.png timeline.png; do
    [ -s "$dir/$png" ] || fail "$dir/$png is missing"
    [ "$(head -c 8 "$dir/$png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] || fail "$dir/$png is not a PNG"
  done
  say "report: completed, tight in cycle $tight (truly $true_tight), latency $(sed -n 's/.*"latency_ms":[[:space:]]*\({[^}]*}\).*/\1/p' "$report")"
}
check_nothing_left() {
  local what
  for what in "container ls -a" "network ls" "volume ls"; do
    # shellcheck disable=SC2086
    [ -z "$(docker $what -q --filter "label=com.docker.compose.project=$project")" ] ||
      fail "docker $what: something of project $project is left after down"
  done
}

# --- Plain, from a folder that does not exist yet ---------------------------------------------
say "plain run (build, up, down)"
bash scripts/run-compose --project "$project" --out "$work/plain/out" 2>&1 | tee "$work/plain.log" >&2 ||
  fail "run-compose failed (status ${PIPESTATUS[0]})"
check_report "$work/plain/out"
check_nothing_left

# --- CURVE --------------------------------------------------------------------------------------
say "CURVE run"
TACTILE_KEYS=$work/keys bash scripts/run-compose --curve --no-build --project "$project" --out "$work/curve" \
  2>&1 | tee "$work/curve.log" >&2 || fail "run-compose --curve failed (status ${PIPESTATUS[0]})"
check_report "$work/curve"
grep -q "publishing on tcp://.*(CURVE)" "$work/curve.log" || fail "sensor_node did not publish under CURVE"
grep -q "events on tcp://.*(CURVE)" "$work/curve.log" || fail "hand_node did not publish its events under CURVE"
[ "$(stat -c %a "$work/keys/arm.key")" = 600 ] || fail "the arm's key file is not mode 0600"
check_nothing_left

# --- A folder the rig cannot write: an error on screen and a non-zero status, not an empty folder
say "a report folder the rig cannot write"
mkdir -m 0755 "$work/readonly"
status=0
TACTILE_UID=10001 TACTILE_GID=10001 bash scripts/run-compose --no-build --project "$project" \
  --out "$work/readonly" >"$work/readonly.log" 2>&1 || status=$?
[ "$status" != 0 ] || fail "run-compose exited 0 although the rig could not write its report"
grep -q "rig: /out: cannot write here" "$work/readonly.log" ||
  { tail -n 30 "$work/readonly.log" >&2; fail "the rig's refusal did not reach the screen"; }
check_nothing_left

stop_engine
if [ -n "$saved_rules" ]; then
  diff -u "$saved_rules" <(nft list ruleset) >&2 || fail "the firewall ruleset differs from the one found"
fi
say "passed"
