#!/usr/bin/env bash
# The compose rig for real (docs/docker.md): a Docker engine (the machine's, or dockerd started
# here and stopped after, the machine's firewall and forwarding left as they were found), base
# images made locally when absent, the image built, a folder the rig cannot write refused on
# screen, a run killed (SIGKILL) mid-way, then the default scenario under docker-compose plain
# and with CURVE by the documented command at once on the one engine (each on networks of its
# own), which remove what the killed run left and say so; the reports and plots checked, and
# nothing left behind by `down`. A test killed before its end leaves its engine's state to the
# next, which restores the machine first (docs/reliability.md, "What a killed run leaves").
#
#   compose_test.sh SOURCE_DIR
#
# Exit 0 on success, 1 on a failure (the line says which check), 77 when it cannot run here (no
# engine answers and this is not root, so none can be started): ctest counts that as skipped.
set -euo pipefail
src=$(cd "${1:?usage: compose_test.sh SOURCE_DIR}" && pwd)
cd "$src"

# shellcheck source=scripts/lib/leftovers.sh
source scripts/lib/leftovers.sh
owner=$(owner_of $$)
# Named after its owner: what a killed test left (its dockerd, the machine's state it saved) is
# found by the next.
work=/var/tmp/compose-test.${owner/:/-}
mkdir "$work"
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
    if [ -s "$saved_rules.$s" ]; then sysctl -qw "$s=$(cat "$saved_rules.$s")" || true; fi
  done
  if [ -e "$saved_rules.no-docker0" ] && ip link show docker0 >/dev/null 2>&1; then ip link delete docker0; fi
}
# stop_dockerd DIR: the dockerd whose pidfile is in DIR (that process, not another that took its
# PID), and waits until it has gone.
stop_dockerd() {
  local pid
  pid=$(cat "$1/dockerd.pid" 2>/dev/null || true)
  [[ "$(tr '\0' ' ' 2>/dev/null <"/proc/$pid/cmdline")" == *" --pidfile $1/dockerd.pid "* ]] || return 0
  if [ -n "$pid" ] && kill "$pid" 2>/dev/null; then
    for _ in $(seq 1 100); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
    kill -0 "$pid" 2>/dev/null && kill -9 "$pid" 2>/dev/null || true
  fi
}
stop_engine() {
  [ "$started_engine" = 1 ] || return 0
  stop_dockerd "$work"
  restore_machine
  started_engine=0
}
projects=()
cleanup() {
  local status=$? p
  if [ -n "${compose_cmd:-}" ]; then
    for p in "${projects[@]}"; do
      "${compose_cmd[@]}" -p "$p" -f docker/compose.yaml -f docker/compose.curve.yaml \
        down --volumes --remove-orphans >/dev/null 2>&1 || true
    done
  fi
  stop_engine
  rm -rf "$work"
  exit "$status"
}
trap cleanup EXIT

# A test killed before its end: its dockerd (told to stop when the test ended) and the machine's
# firewall and forwarding as that test found them, saved in its folder.
for dir in /var/tmp/compose-test.*-*; do
  dead=${dir#/var/tmp/compose-test.}
  if ! [[ "$dead" =~ ^[0-9]+-[0-9]+$ ]] || ! owner_gone "${dead/-/:}"; then continue; fi
  stop_dockerd "$dir"
  restored="the engine that answers now kept"
  # Only when that test started the engine (it saved the machine first) and none runs now.
  if [ -e "$dir/ruleset.nft" ] && ! docker info >/dev/null 2>&1; then
    saved_rules=$dir/ruleset.nft restore_machine
    restored="the firewall and forwarding it found restored"
  fi
  rm -rf "$dir"
  say "removed $dir left by an earlier run (pid ${dead%%-*}, no longer running): its dockerd stopped, $restored"
done

if docker info >/dev/null 2>&1; then
  say "using the Docker engine that answers here ($(docker info -f '{{.ServerVersion}}'))"
else
  if [ "$(id -u)" != 0 ]; then
    say "no Docker engine answers and starting one needs root: cannot run here"
    exit 77
  fi
  command -v dockerd >/dev/null 2>&1 || fail "dockerd is missing (bash scripts/install-deps --test installs docker.io)"
  # Empty when nft is missing or the ruleset is: the file says that this test saved the machine.
  saved_rules=$work/ruleset.nft
  : >"$saved_rules"
  if command -v nft >/dev/null 2>&1; then nft list ruleset >"$saved_rules"; fi
  for s in net.ipv4.ip_forward net.ipv6.conf.all.forwarding; do
    sysctl -n "$s" >"$saved_rules.$s" 2>/dev/null || true
  done
  ip link show docker0 >/dev/null 2>&1 || touch "$saved_rules.no-docker0"
  say "starting dockerd (log: $work/dockerd.log)"
  started_engine=1
  # Told to stop (SIGTERM) when this test ends, even by SIGKILL.
  setpriv --pdeathsig TERM -- dockerd --data-root /var/lib/docker --pidfile "$work/dockerd.pid" \
    >"$work/dockerd.log" 2>&1 &
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
check_nothing_left() {  # check_nothing_left PROJECT
  local what
  for what in "container ls -a" "network ls" "volume ls"; do
    # shellcheck disable=SC2086
    [ -z "$(docker $what -q --filter "label=com.docker.compose.project=$1")" ] ||
      fail "docker $what: something of project $1 is left"
  done
}

# --- A folder the rig cannot write: an error on screen and a non-zero status, not an empty folder
# (and the image built by the documented command)
say "a report folder the rig cannot write (build, up, down)"
mkdir -m 0755 "$work/readonly"
projects+=("$project-readonly")
status=0
TACTILE_UID=10001 TACTILE_GID=10001 bash scripts/run-compose --project "$project-readonly" \
  --out "$work/readonly" >"$work/readonly.log" 2>&1 || status=$?
[ "$status" != 0 ] || fail "run-compose exited 0 although the rig could not write its report"
grep -q "rig: /out: cannot write here" "$work/readonly.log" ||
  { tail -n 30 "$work/readonly.log" >&2; fail "the rig's refusal did not reach the screen"; }
check_nothing_left "$project-readonly"

# --- A run killed (SIGKILL) once its containers run: they and its networks stay for the next ----
say "a run killed mid-way"
projects+=("$project-killed")
bash scripts/run-compose --no-build --project "$project-killed" --out "$work/killed" \
  >"$work/killed.log" 2>&1 &
killed=$!
for _ in $(seq 1 300); do
  [ -n "$(docker container ls -q --filter "label=com.docker.compose.project=$project-killed")" ] && break
  sleep 0.2
done
[ -n "$(docker container ls -q --filter "label=com.docker.compose.project=$project-killed")" ] ||
  { cat "$work/killed.log" >&2; fail "the run to be killed started no container in 60 s"; }
sleep 2
kill -KILL "$killed"
wait "$killed" 2>/dev/null || true

# --- Plain and CURVE at once on the one engine, from folders that do not exist yet -------------
say "plain and CURVE runs at once"
projects+=("$project-plain" "$project-curve")
bash scripts/run-compose --no-build --project "$project-plain" --out "$work/plain/out" \
  >"$work/plain.log" 2>&1 &
plain=$!
TACTILE_KEYS=$work/keys bash scripts/run-compose --curve --no-build --project "$project-curve" \
  --out "$work/curve" >"$work/curve.log" 2>&1 &
curve=$!
status=0
wait "$plain" || status=$?
[ "$status" = 0 ] || { cat "$work/plain.log" >&2; fail "run-compose failed (status $status)"; }
status=0
wait "$curve" || status=$?
[ "$status" = 0 ] || { cat "$work/curve.log" >&2; fail "run-compose --curve failed (status $status)"; }
grep -h "run-compose: starting" "$work/plain.log" "$work/curve.log" >&2
check_report "$work/plain/out"
check_report "$work/curve"
grep -q "publishing on tcp://.*(CURVE)" "$work/curve.log" || fail "sensor_node did not publish under CURVE"
grep -q "events on tcp://.*(CURVE)" "$work/curve.log" || fail "hand_node did not publish its events under CURVE"
[ "$(stat -c %a "$work/keys/arm.key")" = 600 ] || fail "the arm's key file is not mode 0600"
# The killed run's containers and networks, removed by one of the two with a line naming each.
killed_removed=$(grep -h "run-compose: removed .* ${project}-killed.* left by an earlier run (pid $killed, no longer running)" \
  "$work/plain.log" "$work/curve.log" || true)
echo "$killed_removed" >&2
echo "$killed_removed" | grep -q "removed container" || fail "no run said it removed the killed run's containers"
echo "$killed_removed" | grep -q "removed network" || fail "no run said it removed the killed run's networks"
for p in killed plain curve; do check_nothing_left "$project-$p"; done

stop_engine
if [ -n "$saved_rules" ]; then
  diff -u "$saved_rules" <(nft list ruleset) >&2 || fail "the firewall ruleset differs from the one found"
fi
say "passed"
