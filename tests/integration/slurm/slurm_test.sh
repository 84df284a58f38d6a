#!/usr/bin/env bash
# The sweep and the training on a real Slurm scheduler (docs/slip.md, "On a Slurm cluster"):
# starts a one-host cluster from Debian's packages (munged, slurmctld, slurmd) with its key,
# configuration, state, logs and sockets in a temporary folder and ports of its own, runs
# scripts/sweep-slurm on it and compares with one machine's run, byte for byte; kills a shard mid-run
# and checks it is found and run again (only its missing scenarios) to the same table; then trains
# from shards, one of them killed (SIGKILL) and run again, to one process's model. Stops
# everything it started and checks the machine is left as found.
#
#   bash slurm_test.sh SOURCE_DIR RIG SLIP_TRAIN        (as root)
set -euo pipefail

src=$1 rig=$2 slip_train=$3
fail() { echo "FAIL: $*" >&2; exit 1; }
say() { echo "slurm_test: $*" >&2; }

[ "$(id -u)" = 0 ] || fail "this test needs root: it starts munged, slurmctld and slurmd (CI runs as root); run it as root, or leave it out with ctest -LE slurm"
for p in munged mungekey munge slurmctld slurmd sbatch squeue scancel sinfo; do
  command -v "$p" >/dev/null || [ -x "/usr/sbin/$p" ] ||
    fail "$p is not installed: bash scripts/install-deps --test installs slurmctld slurmd slurm-client munge"
done
ctld_port=16817 slurmd_port=16818
for port in $ctld_port $slurmd_port; do
  ! ss -Hltn "sport = :$port" | grep -q . || fail "port $port is in use (another run of this test?)"
done

# The machine as found: the places munge and Slurm use by default, and their processes.
found() {
  ls -lA --time-style=+%s /etc/slurm /etc/munge /var/log/slurm /var/log/munge /var/lib/munge 2>&1 || true
  ls -d /var/spool/slurm* /run/munge /run/slurm* 2>&1 | sort || true
}
# (A dead daemon stays a zombie for a while where PID 1 is no init: not running.)
daemons() {
  ps -eo pid=,stat=,comm= |
    awk '$2 !~ /^Z/ && $3 ~ /^(munged|slurmctld|slurmd|slurmstepd|slurmscriptd)$/ { print $1 }' | sort
}
before=$(found)
procs_before=$(daemons)

tmp=$(mktemp -d /tmp/slurm_test.XXXXXX)
chmod 0711 "$tmp"  # munged wants its socket's folders searchable by all
cluster=$tmp/cluster work=$tmp/work
mkdir -p "$cluster/state" "$cluster/spool" "$work"
export SLURM_CONF=$cluster/slurm.conf

# Stops what it started: the jobs, slurmd and slurmctld, the job steps they leave, munged.
stop_daemon() {  # NAME: the daemon of that name whose pid file is in the cluster folder
  local pid
  pid=$(cat "$cluster/$1.pid" 2>/dev/null) || return 0
  [ "$(ps -o comm= -p "$pid" 2>/dev/null)" = "$1" ] || return 0
  kill -TERM "$pid"
  for _ in $(seq 100); do
    [[ "$(ps -o stat= -p "$pid" 2>/dev/null || echo Z)" == Z* ]] && return 0
    sleep 0.1
  done
  kill -KILL "$pid"
}
stop() {
  set +e
  if [ -s "$cluster/slurmctld.pid" ]; then
    scancel -u root 2>/dev/null
    for _ in $(seq 100); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.2; done
  fi
  stop_daemon slurmd
  stop_daemon slurmctld
  # Job steps and what they run outlive slurmd: those that were not here before.
  for pid in $(pgrep -x slurmstepd); do
    grep -qx "$pid" <<<"$procs_before" || pkill -KILL -s "$(ps -o sid= -p "$pid" | tr -d ' ')"
  done
  # munged last: slurmctld saves its state and slurmd ends its steps with munge's help.
  stop_daemon munged
  for _ in $(seq 100); do
    [ "$(daemons)" = "$procs_before" ] && break
    sleep 0.1
  done
  rm -rf "$tmp"
}
trap stop EXIT

# --- the cluster --------------------------------------------------------------------------------
node=$(hostname -s)
mungekey --create --keyfile="$cluster/munge.key"
chmod 0400 "$cluster/munge.key"
/usr/sbin/munged --force --socket="$cluster/munge.socket" --key-file="$cluster/munge.key" \
  --log-file="$cluster/munged.log" --pid-file="$cluster/munged.pid" --seed-file="$cluster/munged.seed"
cat >"$SLURM_CONF" <<CONF
ClusterName=tactiletest
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
AuthType=auth/munge
AuthInfo=socket=$cluster/munge.socket
CredType=cred/munge
StateSaveLocation=$cluster/state
SlurmdSpoolDir=$cluster/spool
SlurmctldPidFile=$cluster/slurmctld.pid
SlurmdPidFile=$cluster/slurmd.pid
SlurmctldLogFile=$cluster/slurmctld.log
SlurmdLogFile=$cluster/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
SchedulerParameters=batch_sched_delay=0
DependencyParameters=kill_invalid_depend
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/none
JobCompType=jobcomp/none
MailProg=/bin/true
ReturnToService=2
KillWait=5
SlurmdTimeout=30
NodeName=$node NodeAddr=127.0.0.1 CPUs=$(nproc) State=UNKNOWN
PartitionName=debug Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
/usr/sbin/slurmctld
/usr/sbin/slurmd
state=""
for _ in $(seq 100); do
  state=$(sinfo -h -n "$node" -o %T 2>/dev/null || true)
  [ "$state" = idle ] && break
  sleep 0.2
done
if [ "$state" != idle ]; then
  tail -n 20 "$cluster"/*.log >&2
  fail "the node is '$state', not idle, 20 s after the start"
fi
say "a one-host cluster is up (node $node)"

# A lab's calibration file that is not there: a usage error before anything is submitted.
set +e
bash "$src/scripts/sweep-slurm" sweep --scenarios 2 --seed 23 --shards 2 --out "$work/nofile" \
  --rig "$rig" --calibration "$work/no-such.yaml" 2>"$work/nofile.log"
rc=$?
set -e
[ "$rc" = 2 ] && grep -q "no-such.yaml" "$work/nofile.log" ||
  fail "sweep-slurm --calibration of a missing file: exit $rc, $(cat "$work/nofile.log")"

# --- the sweep ----------------------------------------------------------------------------------
sweep=(--scenarios 6 --seed 23 --max-sim-time 6 --detectors paper)
"$rig" --sweep 6 --seed 23 --max-sim-time 6 --detectors paper --jobs 2 --out "$work/whole" \
  >/dev/null 2>"$work/whole.log" || fail "the single-machine sweep failed: $(tail -n 3 "$work/whole.log")"

bash "$src/scripts/sweep-slurm" sweep "${sweep[@]}" --shards 3 --out "$work/plain" --rig "$rig" --poll 0.3 \
  --timeout 120 2>"$work/plain.log" || { cat "$work/plain.log" >&2; fail "sweep-slurm sweep failed"; }
cmp "$work/whole/sweep.csv" "$work/plain/merged/sweep.csv" || fail "the merged sweep.csv differs from one machine's"
cmp "$work/whole/summary.md" "$work/plain/merged/summary.md" || fail "the merged summary.md differs"
grep -q "round 0:" "$work/plain.log" && ! grep -q "round 1:" "$work/plain.log" ||
  fail "a sweep with no failure ran a second round: $(cat "$work/plain.log")"
say "3 shards and the merge on Slurm: the same table and summary as one machine"

# Shard 2 of 3 (scenarios 1 and 4) killed once its first scenario is done: scancel, as a user
# or the scheduler (a time limit, a preemption) does.
bash "$src/scripts/sweep-slurm" sweep "${sweep[@]}" --shards 3 --out "$work/killed" --rig "$rig" --poll 0.3 \
  --timeout 120 2>"$work/killed.log" &
script=$!
killed=""
for _ in $(seq 600); do
  if compgen -G "$work/killed/shard-2/reports/*.json" >/dev/null && [ ! -e "$work/killed/shard-2/sweep.json" ]; then
    task=$(squeue -h -n sweep-shard -o '%F_%K' | grep '_2$' || true)
    if [ -n "$task" ]; then scancel "$task"; killed=$task; break; fi
  fi
  sleep 0.1
done
[ -n "$killed" ] || { kill "$script"; fail "shard 2 was never seen running with a scenario done"; }
wait "$script" || { cat "$work/killed.log" >&2; fail "sweep-slurm did not recover from the killed shard"; }
cat "$work/killed.log" >&2
grep -q "shards 2 did not finish" "$work/killed.log" || fail "the killed shard was not found"
grep -q "resuming: 1 runs kept from their reports, 1 to run" "$work/killed/slurm/shard-2-round-1.log" ||
  fail "the rerun did not run only the missing scenario: $(cat "$work/killed/slurm/shard-2-round-1.log")"
cmp "$work/whole/sweep.csv" "$work/killed/merged/sweep.csv" || fail "after the rerun, sweep.csv differs"
cmp "$work/whole/summary.md" "$work/killed/merged/summary.md" || fail "after the rerun, summary.md differs"
say "shard $killed killed mid-run, found and resumed: still the same table"

# --- the training -------------------------------------------------------------------------------
train=(--scenarios 2 --max-time 6 --grip mixed --trees 4 --depth 3)
"$slip_train" --seeds 5,6 "${train[@]}" --jobs 2 --out "$work/whole.inc" 2>"$work/train-whole.log" ||
  fail "slip_train on one machine failed: $(tail -n 3 "$work/train-whole.log")"
# Shard 2 of 3 (run 1 of 4) killed with SIGKILL while slip_train runs, as the kernel's OOM
# killer does: no rows file, the job FAILED; it runs again whole.
bash "$src/scripts/sweep-slurm" train --seeds 5,6 "${train[@]}" --shards 3 --out "$work/train" \
  --slip-train "$slip_train" --poll 0.3 --timeout 120 2>"$work/train.log" &
script=$!
killed=""
for _ in $(seq 600); do
  # The one process whose arguments name this test's own shard-2 rows file.
  for pid in $(pgrep -x slip_train); do
    if tr '\0' ' ' <"/proc/$pid/cmdline" 2>/dev/null | grep -qF -- "--rows-out $work/train/rows/shard-2.rows"; then
      kill -KILL "$pid" && killed=$pid
    fi
  done
  [ -z "$killed" ] || break
  sleep 0.1
done
[ -n "$killed" ] || { kill "$script"; fail "shard 2's slip_train was never seen running"; }
wait "$script" || { cat "$work/train.log" >&2; fail "sweep-slurm train failed"; }
cat "$work/train.log" >&2
grep -q "shards 2 did not finish" "$work/train.log" || fail "the killed training shard was not found"
cmp "$work/whole.inc" "$work/train/slip_model.inc" || fail "the model fitted from the shards' rows differs"
say "training rows from 3 shards (one killed and run again), fitted once: the same model as one machine"

# --- the machine as found -----------------------------------------------------------------------
trap - EXIT
stop
[ ! -e "$tmp" ] || fail "$tmp is left"
[ "$(daemons)" = "$procs_before" ] || fail "daemons left running: $(comm -13 <(echo "$procs_before") <(daemons))"
[ "$(found)" = "$before" ] || fail "the machine's munge and Slurm places changed: $(diff <(echo "$before") <(found))"
for port in $ctld_port $slurmd_port; do
  ! ss -Hltn "sport = :$port" | grep -q . || fail "port $port is still open"
done
say "PASS: everything stopped and removed"
