#!/usr/bin/env bash
# A run killed with SIGKILL mid-run leaves nothing that stops the next one (docs/reliability.md,
# "What a killed run leaves"): its children die with it, the next run on the same addresses starts
# (removing, and naming, what the killed run could not), and the machine ends as it was found:
# no network namespace (`ip netns list`), link (`ip -o link`) or nft rule more, no process of the
# runs left.
#
#   killed_run_test.sh SOURCE_DIR BUILD_DIR run-system|camera-link|bench-gige-link|namespaced|compose-test
#
# Root only (namespaces and veth pairs on the host). Exit 0 on success, 1 on a failure (the line
# says which check), 77 for compose-test when a Docker engine already runs here (ctest: skipped).
set -euo pipefail
src=$(cd "${1:?usage: killed_run_test.sh SOURCE_DIR BUILD_DIR WHICH}" && pwd)
build=$(cd "${2:?usage: killed_run_test.sh SOURCE_DIR BUILD_DIR WHICH}" && pwd)
which=${3:?usage: killed_run_test.sh SOURCE_DIR BUILD_DIR WHICH}
cd "$src"

say() { echo "killed_run_test: $which: $*" >&2; }
fail() {
  say "FAILED: $*"
  exit 1
}
[ "$(id -u)" = 0 ] || fail "needs root (CI runs as root)"
work=$(mktemp -d /tmp/killed-run.XXXXXX)
pids=()
# shellcheck disable=SC2317 # called from the trap
cleanup() {
  local p
  for p in "${pids[@]}"; do kill -KILL "$p" 2>/dev/null || true; done
  for p in "tkd$$" "tkl$$"; do ip link del "$p" 2>/dev/null || true; done
  rm -rf "$work"
}
trap cleanup EXIT

# What a run may add to the machine: namespaces, links, firewall rules.
machine() {
  ip netns list | sed 's/ .*//' | sort
  ip -o link show | sed 's/^[0-9]*: \([^:@]*\).*/link \1/' | sort
  nft list ruleset 2>/dev/null || true
}
# The processes of the runs: every one of them names a path under $work.
runs_processes() {
  local f
  for f in /proc/[0-9]*/cmdline; do
    if tr '\0' ' ' 2>/dev/null <"$f" | grep -qF "$work/"; then
      f=${f#/proc/}
      echo "${f%/cmdline}: $(tr '\0' ' ' 2>/dev/null <"/proc/$f")"
    fi
  done
}
# await_line FILE REGEX [SECONDS]: until FILE has a line matching REGEX.
await_line() {
  local i
  for ((i = 0; i < ${3:-30} * 10; i++)); do
    if grep -Eq "$2" "$1" 2>/dev/null; then return 0; fi
    sleep 0.1
  done
  return 1
}
# The machine as found, and no process of the runs, within 20 s of the last kill.
check_as_before() {
  local i now=""
  for ((i = 0; i < 200; i++)); do
    now=$(machine)
    if [ "$now" = "$before" ] && [ -z "$(runs_processes)" ]; then
      say "the machine is as before and no process of the runs is left ($((i / 10)).$((i % 10)) s after the kill)"
      return 0
    fi
    sleep 0.1
  done
  diff -u <(echo "$before") <(echo "$now") >&2 || true
  runs_processes >&2
  fail "20 s after the kill, the machine is not as before or a process of the runs is left (above)"
}

case "$which" in
  run-system)
    # A scenario cut short at 8 s, on a network of its own (beside the user's and the other
    # tests'), with a recorder: the child that outlived a killed run before.
    net=10.77.29.0/30
    run() {
      bash scripts/run-system --build "$build" --scenario tests/data/scenarios/observe.yaml \
        --out "$work/$1" --record "$work/$1.tlog" --host-net "$net" 2>"$work/$1.log" &
      pids+=($!)
    }
    # A veth pair labelled by a run that no longer runs (a stand-in for one killed where the
    # kernel could not help), and one by a run that does (this script): the first goes, the
    # second stays.
    # shellcheck source=scripts/lib/leftovers.sh
    source scripts/lib/leftovers.sh
    before=$(machine)
    sleep 0.2 &
    dead_owner=$(owner_of $!)
    wait
    ip link add "tkd$$" type veth peer name "tkdp$$"
    ip link set dev "tkd$$" alias "tactile-run-system:$dead_owner"
    ip link add "tkl$$" type veth peer name "tklp$$"
    ip link set dev "tkl$$" alias "tactile-run-system:$(owner_of $$)"
    run first
    await_line "$work/first.log" "run-system: starting the rig" ||
      fail "the first run did not start: $(tail -n 3 "$work/first.log")"
    grep -q "run-system: removed veth tkd$$ left by an earlier run (pid ${dead_owner%%:*}, no longer running)" \
      "$work/first.log" || fail "the dead run's veth was not removed with a message: $(cat "$work/first.log")"
    ip link show dev "tkl$$" >/dev/null 2>&1 || fail "the veth of a run that still runs was removed"
    ip link del "tkl$$"
    sleep 2
    kill -KILL "${pids[0]}"
    wait "${pids[0]}" 2>/dev/null || true
    say "killed the first run (SIGKILL) while its nodes and recorder ran"
    # The next run at once, on the same network.
    run second
    await_line "$work/second.log" "run-system: (starting the rig|.*in use|.*failed)" ||
      fail "the second run said nothing in 30 s: $(cat "$work/second.log")"
    grep -q "run-system: starting the rig" "$work/second.log" ||
      fail "the second run did not start: $(cat "$work/second.log")"
    grep "removed veth" "$work/second.log" >&2 || true
    sleep 2
    kill -KILL "${pids[1]}"
    wait "${pids[1]}" 2>/dev/null || true
    say "killed the second run (SIGKILL)"
    check_as_before
    ;;
  camera-link)
    before=$(machine)
    bash scripts/camera-link separate >"$work/link.out" 2>"$work/link.log" &
    pids+=($!)
    await_line "$work/link.out" "^cameras " || fail "camera-link did not come up: $(cat "$work/link.log")"
    holder=$(sed -n 's|.* netns /proc/\([0-9]*\)/ns/net .*|\1|p' "$work/link.out")
    kill -KILL "${pids[0]}"
    wait "${pids[0]}" 2>/dev/null || true
    say "killed camera-link (SIGKILL)"
    for _ in $(seq 100); do kill -0 "$holder" 2>/dev/null || break; sleep 0.1; done
    ! kill -0 "$holder" 2>/dev/null || fail "the cameras' namespace's holder (pid $holder) outlived camera-link"
    check_as_before
    ;;
  bench-gige-link)
    before=$(machine)
    run() {
      bash scripts/bench-gige-link --build "$build" --out "$work/$1" --seconds 5 --topologies shared \
        --rois full >"$work/$1.out" 2>"$work/$1.log" &
      pids+=($!)
    }
    run first
    # Mid-run: the cameras serve and sensor_node is starting.
    await_line "$work/first.log" "bench-gige-link: shared-full:" || fail "the first run did not start: $(cat "$work/first.log")"
    sleep 2
    first_namespaces=$(ip netns list | sed -n 's/^\(tactile-gige-[0-9-]*-\(cam\|sens\)\).*/\1/p' | sort)
    [ "$(echo "$first_namespaces" | wc -l)" = 2 ] || fail "not the run's two namespaces: $first_namespaces"
    kill -KILL "${pids[0]}"
    wait "${pids[0]}" 2>/dev/null || true
    say "killed the first run (SIGKILL) while its cameras ran"
    # Its cameras and sensor_node die with it.
    for ns in $first_namespaces; do
      for _ in $(seq 50); do [ -z "$(ip netns pids "$ns")" ] && break; sleep 0.1; done
      [ -z "$(ip netns pids "$ns")" ] || fail "processes outlived the killed run in $ns: $(ip netns pids "$ns")"
    done
    run second
    for ns in $first_namespaces; do
      await_line "$work/second.log" "bench-gige-link: removed namespace $ns left by an earlier run \(pid ${pids[0]}, no longer running\)" 10 ||
        fail "the second run did not remove $ns with a message: $(cat "$work/second.log")"
    done
    await_line "$work/second.log" "bench-gige-link: shared-full:" || fail "the second run did not start: $(cat "$work/second.log")"
    sleep 1
    # Its namespaces are named, so the kernel cannot remove them: a stop (SIGTERM) does.
    kill -TERM "${pids[1]}"
    wait "${pids[1]}" || true
    check_as_before
    ;;
  namespaced)
    # The compose topology's test: killed, its nodes die with it (PR_SET_PDEATHSIG) and its four
    # named namespaces stay until the next run of it removes them.
    before=$(machine)
    tmp_before=$(find /tmp -maxdepth 1 -name 'tactile-proc-*' | sort)
    test=$build/tests/integration/system/namespaced_system_test
    # Its programs' output folders (tests/support/process.cpp) go under $work: a killed test cannot
    # remove them, and each CI run left three in /tmp before.
    TMPDIR=$work "$test" --gtest_filter=NamespacedSystem.RunsTheComposeTopologyWithDockersConfiguration \
      >"$work/first.log" 2>&1 &
    pids+=($!)
    for _ in $(seq 300); do
      [ "$(ip netns list | grep -c "^tsc-[a-z]*-${pids[0]}-")" = 4 ] && break
      sleep 0.1
    done
    [ "$(ip netns list | grep -c "^tsc-[a-z]*-${pids[0]}-")" = 4 ] || fail "the test's four namespaces did not come up"
    sleep 3
    kill -KILL "${pids[0]}"
    wait "${pids[0]}" 2>/dev/null || true
    say "killed the test (SIGKILL) while its nodes ran"
    for ns in $(ip netns list | sed -n "s/^\(tsc-[a-z]*-${pids[0]}-[0-9]*\).*/\1/p"); do
      for _ in $(seq 100); do [ -z "$(ip netns pids "$ns")" ] && break; sleep 0.1; done
      [ -z "$(ip netns pids "$ns")" ] || fail "processes outlived the killed test in $ns: $(ip netns pids "$ns")"
    done
    "$test" --gtest_filter=NamespacedSystem.RemovesTheNamespacesOfAKilledRunAndNoOthers \
      >"$work/second.log" 2>&1 || fail "the next run failed: $(cat "$work/second.log")"
    [ "$(grep -c "removed namespace tsc-[a-z]*-${pids[0]}-[0-9]* left by an earlier run (pid ${pids[0]}, no longer running)" "$work/second.log")" = 4 ] ||
      fail "the next run did not remove the four namespaces with a line each: $(cat "$work/second.log")"
    [ "$(find /tmp -maxdepth 1 -name 'tactile-proc-*' | sort)" = "$tmp_before" ] ||
      fail "the runs left folders in /tmp: $(comm -13 <(echo "$tmp_before") <(find /tmp -maxdepth 1 -name 'tactile-proc-*' | sort))"
    [ -n "$(find "$work" -maxdepth 1 -name 'tactile-proc-*')" ] ||
      fail "the killed test's folders are not under $work (TMPDIR not honoured?)"
    check_as_before
    ;;
  compose-test)
    # The compose test (tests/integration/docker) killed once the dockerd it started answers: the
    # dockerd stops with it, and the next test restores the firewall and forwarding the killed one
    # found (its folder holds them) before it starts an engine of its own.
    if docker info >/dev/null 2>&1; then
      say "a Docker engine already answers here: the compose test would start none"
      exit 77
    fi
    # The engine's processes count as the machine here: the next start of dockerd waits for a
    # containerd that is still ending (and gave up after 30 s once).
    machine() {
      ip netns list | sed 's/ .*//' | sort
      ip -o link show | sed 's/^[0-9]*: \([^:@]*\).*/link \1/' | sort
      nft list ruleset 2>/dev/null || true
      { pgrep -x dockerd || true; } | sed 's/^/dockerd /'
      { pgrep -x containerd || true; } | sed 's/^/containerd /'
    }
    before=$(machine)
    forwarding=$(sysctl -n net.ipv4.ip_forward)
    before_rules=$(nft list ruleset 2>/dev/null)
    compose_test() {
      bash tests/integration/docker/compose_test.sh . >"$work/$1.log" 2>&1 &
      pids+=($!)
    }
    compose_test first
    for _ in $(seq 150); do docker info >/dev/null 2>&1 && break; sleep 0.2; done
    docker info >/dev/null 2>&1 || fail "the first test's dockerd did not answer: $(cat "$work/first.log")"
    kill -KILL "${pids[0]}"
    wait "${pids[0]}" 2>/dev/null || true
    say "killed the first test (SIGKILL) once its dockerd answered"
    for _ in $(seq 100); do docker info >/dev/null 2>&1 || break; sleep 0.2; done
    ! docker info >/dev/null 2>&1 || fail "the first test's dockerd outlived it by 20 s"
    compose_test second
    await_line "$work/second.log" "compose_test: removed /var/tmp/compose-test\.${pids[0]}-[0-9]+ left by an earlier run \(pid ${pids[0]}, no longer running\): its dockerd stopped, the firewall and forwarding it found restored" ||
      fail "the second test did not restore what the first left: $(cat "$work/second.log")"
    saved=$(echo /var/tmp/compose-test."${pids[1]}"-*)
    for _ in $(seq 50); do [ -e "$saved/ruleset.nft.net.ipv4.ip_forward" ] && break; sleep 0.1; done
    [ "$(cat "$saved/ruleset.nft")" = "$before_rules" ] ||
      fail "the second test found another ruleset than the first: $(diff <(echo "$before_rules") "$saved/ruleset.nft")"
    [ "$(cat "$saved/ruleset.nft.net.ipv4.ip_forward")" = "$forwarding" ] ||
      fail "the second test found forwarding $(cat "$saved/ruleset.nft.net.ipv4.ip_forward"), not $forwarding"
    # A stop (SIGTERM) ends the second as a test ends: its engine stopped, the machine restored.
    kill -TERM "${pids[1]}"
    wait "${pids[1]}" 2>/dev/null || true
    [ "$(sysctl -n net.ipv4.ip_forward)" = "$forwarding" ] || fail "forwarding is not as found"
    ! ls -d /var/tmp/compose-test."${pids[0]}"-* /var/tmp/compose-test."${pids[1]}"-* 2>/dev/null ||
      fail "a test's folder is left"
    check_as_before
    ;;
  *) fail "give run-system, camera-link, bench-gige-link, namespaced or compose-test" ;;
esac
say "passed"
