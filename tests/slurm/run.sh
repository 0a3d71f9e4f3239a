#!/usr/bin/env bash
# Integration test on a real single-node Slurm cluster on this machine: the smoke delayed
# TR-NEWS sweep as a 4-task job array plus the dependent merge job (both written and submitted
# by `trnews-script slurm`) must give the same figures and tables as a local run.
#
# Usage: tests/slurm/run.sh TRNEWS_SCRIPT_BINARY
# Exit status: 0 passed, 77 skipped (Slurm is not installed and cannot be installed here;
# the reason is printed), anything else failed.
#
# The cluster is tests/slurm/cluster.sh's.
set -euo pipefail

BIN=$(realpath "${1:?usage: $0 TRNEWS_SCRIPT_BINARY}")
REPO=$(cd "$(dirname "$0")/../.." && pwd)
SCRIPT="$REPO/scripts/sweep_delays.rhai"

# shellcheck source=tests/slurm/cluster.sh
source "$(dirname "$0")/cluster.sh"

# The reference: the same sweep run locally in one piece.
"$BIN" "$SCRIPT" --set resolution=smoke --quiet --out "$TMP/local" 2>"$TMP/local.err"

start=$SECONDS
"$BIN" slurm "$SCRIPT" --array 4 --cpus 1 --time 10:00 --set resolution=smoke \
    --out "$TMP/cluster" --submit | tee "$TMP/submit.out"
wait_for 600 "the array and merge jobs to finish" queue_empty
echo "array + merge finished in $((SECONDS - start)) s"

# 4 array tasks and the merge, all COMPLETED (the completion file lags the queue slightly).
five_done() { [ "$(grep -c 'JobState=' "$TMP/jobcomp.txt" 2>/dev/null)" -ge 5 ]; }
wait_for 30 "5 job completion records" five_done
if grep 'JobState=' "$TMP/jobcomp.txt" | grep -v 'JobState=COMPLETED' >/dev/null; then
    echo "FAILED: not every job completed:"
    cat "$TMP/jobcomp.txt"
    exit 1
fi
grep -o ' Name=[^ ]* JobState=[^ ]*' "$TMP/jobcomp.txt" | sort | uniq -c

# Each simulated point was computed by one array task; the merge computed nothing.
merge_log=$(ls "$TMP"/cluster/slurm/sweep_delays-merge-*.log)
grep -q '(simulated): 6 points, 6 stored before, 0 computed here' "$merge_log" \
    || { echo "FAILED: the merge computed points:"; cat "$merge_log"; exit 1; }
computed=$(cat "$TMP"/cluster/slurm/sweep_delays-[0-9]*_*.log | grep -v '] shard [0-9]*/[0-9]*: ' \
    | grep -o '(simulated): 6 points, [0-9]* stored before, [0-9]* computed here' \
    | sed 's/.*before, \([0-9]*\) computed.*/\1/' | awk '{ s += $1 } END { print s + 0 }')
[ "$computed" = 6 ] || { echo "FAILED: the array tasks computed $computed simulated points, not 6"; exit 1; }

# The same figures and tables as the local run, byte for byte (run times excepted: measured).
status=0
for f in "$TMP"/local/plots/*; do
    name=$(basename "$f")
    [ "$name" = sweep_delays_run_times.csv ] && continue
    if cmp -s "$f" "$TMP/cluster/plots/$name"; then
        echo "same: plots/$name"
    else
        echo "FAILED: plots/$name differs from the local run"
        status=1
    fi
done
[ "$status" = 0 ] && echo "PASSED: Slurm 4-task array + merge = local run"
exit "$status"
