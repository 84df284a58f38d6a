#!/usr/bin/env bash
# slip_train in shards (docs/slip.md, "Training on a cluster"): the rows of two shards
# (--shard K/N --rows-out), fitted once (--rows-in), give the very model of one process that ran
# every run; shards of another training, a shard twice or missing, a cut file are refused.
#
#   bash slip_train_rows_test.sh SLIP_TRAIN
set -euo pipefail
slip_train=$1
fail() { echo "FAIL: $*" >&2; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

runs=(--seeds "5,6" --scenarios 2 --max-time 6)
fit=(--trees 3 --depth 2)
"$slip_train" "${runs[@]}" "${fit[@]}" --jobs 2 --out "$tmp/whole.inc" 2>"$tmp/whole.log" ||
  fail "one process: $(tail -n 3 "$tmp/whole.log")"
for k in 1 2; do
  "$slip_train" "${runs[@]}" --shard "$k/2" --rows-out "$tmp/shard-$k.rows" 2>"$tmp/shard-$k.log" ||
    fail "shard $k: $(tail -n 3 "$tmp/shard-$k.log")"
  grep -q "wrote the rows of 2 runs (shard $k/2)" "$tmp/shard-$k.log" || fail "shard $k: $(cat "$tmp/shard-$k.log")"
done
[ ! -e "$tmp/shard-1.inc" ] && ! grep -q "fitting" "$tmp/shard-1.log" || fail "a shard fitted"
"$slip_train" --rows-in "$tmp/shard-2.rows" "$tmp/shard-1.rows" "${fit[@]}" --out "$tmp/rows.inc" \
  2>"$tmp/rows.log" || fail "fit from rows: $(tail -n 3 "$tmp/rows.log")"
cmp "$tmp/whole.inc" "$tmp/rows.inc" || fail "the model fitted from the shards' rows differs from one process's"

refused() {  # EXIT_STATUS MESSAGE ARGS...: slip_train ARGS fails so, saying MESSAGE
  local want=$1 message=$2 code=0
  shift 2
  "$slip_train" "$@" --out "$tmp/never.inc" 2>"$tmp/err.log" || code=$?
  [ "$code" = "$want" ] || fail "slip_train $*: exit $code, not $want: $(cat "$tmp/err.log")"
  grep -qF -- "$message" "$tmp/err.log" || fail "slip_train $*: no '$message' in: $(cat "$tmp/err.log")"
  [ ! -e "$tmp/never.inc" ] || fail "slip_train $*: wrote a model"
}
refused 1 "2 of 4 runs missing, the first seed 5 scenario 1" --rows-in "$tmp/shard-1.rows"
refused 1 "seed 5 scenario 0 is in $tmp/shard-1.rows too" --rows-in "$tmp/shard-1.rows" "$tmp/shard-1.rows"
"$slip_train" --seeds 5 --scenarios 1 --max-time 6 --shard 1/1 --rows-out "$tmp/other.rows" 2>/dev/null
refused 1 "not shards of one training" --rows-in "$tmp/shard-1.rows" "$tmp/other.rows"
# --grip mixed: shard 2 of 2 holds scenario 1 of each seed, an odd one, so run under the margin
# grip: other rows than the paper grip's shard, and not a shard of the paper grip's training.
"$slip_train" "${runs[@]}" --grip mixed --shard 2/2 --rows-out "$tmp/mixed.rows" 2>"$tmp/mixed.log" ||
  fail "mixed shard: $(tail -n 3 "$tmp/mixed.log")"
head -n 1 "$tmp/mixed.rows" | grep -qF '"grip":"mixed"' || fail "no grip in the rows header: $(head -n 1 "$tmp/mixed.rows")"
head -n 1 "$tmp/shard-2.rows" | grep -qF '"grip":"paper"' || fail "no paper grip in the header: $(head -n 1 "$tmp/shard-2.rows")"
cmp -s <(tail -n +2 "$tmp/mixed.rows") <(tail -n +2 "$tmp/shard-2.rows") &&
  fail "the margin grip's runs logged the paper grip's rows"
refused 1 "grip mixed" --rows-in "$tmp/shard-1.rows" "$tmp/mixed.rows"
# --sensor drawn: the runs render each scenario's drawn sensor: other rows, the header says so,
# and such rows are no shard of the rig sensor's training.
"$slip_train" "${runs[@]}" --sensor drawn --shard 2/2 --rows-out "$tmp/drawn.rows" 2>"$tmp/drawn.log" ||
  fail "drawn shard: $(tail -n 3 "$tmp/drawn.log")"
head -n 1 "$tmp/drawn.rows" | grep -qF '"sensor":"drawn"' || fail "no sensor in the rows header: $(head -n 1 "$tmp/drawn.rows")"
head -n 1 "$tmp/shard-2.rows" | grep -qF '"sensor"' && fail "a rig sensor's header names a sensor: $(head -n 1 "$tmp/shard-2.rows")"
cmp -s <(tail -n +2 "$tmp/drawn.rows") <(tail -n +2 "$tmp/shard-2.rows") &&
  fail "the drawn sensor's runs logged the rig sensor's rows"
refused 1 "sensor drawn" --rows-in "$tmp/shard-1.rows" "$tmp/drawn.rows"
refused 2 "--rows-in takes no --sensor" --rows-in "$tmp/shard-1.rows" --sensor drawn
refused 2 "--sensor" --seeds 5 --scenarios 1 --sensor gaussian
refused 2 "--rows-in takes no --grip" --rows-in "$tmp/shard-1.rows" --grip margin
head -c 200 "$tmp/shard-2.rows" >"$tmp/cut.rows"
refused 1 "cut.rows: the file ends within a run's rows" --rows-in "$tmp/shard-1.rows" "$tmp/cut.rows"
refused 2 "--rows-in takes no --seeds" --rows-in "$tmp/shard-1.rows" --seeds 5,6
refused 2 "--shard needs --rows-out" --seeds 5 --scenarios 1 --shard 1/2
refused 2 "--shard: K/N needs 1 <= K <= N; got '3/2'" --seeds 5 --scenarios 1 --shard 3/2 --rows-out "$tmp/x.rows"
echo "PASS"
