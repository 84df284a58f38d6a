# shellcheck shell=bash
# What a killed run leaves behind (docs/reliability.md, "What a killed run leaves"), sourced by
# the scripts that make objects outside themselves (network namespaces, veth pairs, containers,
# networks). Each such object carries its owner, "PID:START" (START is the process's start time
# in clock ticks since boot, /proc/PID/stat field 22, so that a PID reused by another process is
# not taken for the owner), in a name, link alias or label of its own; a later run removes those
# whose owner no longer runs, says so, and goes on. Nothing is matched by a broad pattern: only
# objects with the script's own label.

# owner_of PID: the owner label of process PID ("PID:START"); fails when it does not run.
owner_of() {
  local stat
  stat=$(cat "/proc/$1/stat" 2>/dev/null) || return 1
  # The fields after the command name, which may hold spaces and parentheses: field 3 is $1.
  # shellcheck disable=SC2086
  set -- ${stat##*) }
  echo "${stat%% *}:${20}"
}

# owner_gone OWNER: true when the process OWNER names ("PID:START") no longer runs.
owner_gone() {
  [ "$(owner_of "${1%%:*}" 2>/dev/null)" != "$1" ]
}
