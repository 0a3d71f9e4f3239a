#!/usr/bin/env bash
# Integration test on a real single-node Slurm cluster on this machine: the smoke delayed
# TR-NEWS sweep as a 4-task job array plus the dependent merge job (both written and submitted
# by `trnews-script slurm`) must give the same figures and tables as a local run.
#
# Usage: tests/slurm/run.sh TRNEWS_SCRIPT_BINARY
# Exit status: 0 passed, 77 skipped (Slurm is not installed and cannot be installed here;
# the reason is printed), anything else failed.
#
# The cluster: Debian's slurmctld, slurmd and slurm-client (installed with apt-get when
# missing), auth/none, every daemon listening on 127.0.0.1 only, state in a temporary
# directory, started in the foreground as children of this script and stopped by their
# process ids on exit. No accounting database: job states come from the job completion
# file (JobCompLoc).
set -euo pipefail

BIN=$(realpath "${1:?usage: $0 TRNEWS_SCRIPT_BINARY}")
REPO=$(cd "$(dirname "$0")/../.." && pwd)
SCRIPT="$REPO/scripts/sweep_delays.rhai"

skip() {
    echo "SKIPPED: Slurm integration test: $*"
    exit 77
}

if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v sbatch >/dev/null; then
    [ "$(id -u)" = 0 ] || skip "slurmctld, slurmd and sbatch are not installed and installing them needs root"
    command -v apt-get >/dev/null || skip "slurmctld, slurmd and sbatch are not installed and there is no apt-get"
    echo "installing slurmctld slurmd slurm-client with apt-get"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq >/dev/null 2>&1 || skip "apt-get update failed (no package registry reachable?)"
    apt-get install -y -qq --no-install-recommends slurmctld slurmd slurm-client >/dev/null 2>&1 \
        || skip "apt-get install slurmctld slurmd slurm-client failed"
fi

TMP=$(mktemp -d /tmp/trnews-slurm.XXXXXX)
CTLD_PID=""
SLURMD_PID=""
cleanup() {
    local status=$?
    [ -n "$SLURMD_PID" ] && kill -TERM "$SLURMD_PID" 2>/dev/null || true
    [ -n "$CTLD_PID" ] && kill -TERM "$CTLD_PID" 2>/dev/null || true
    [ -n "$SLURMD_PID" ] && wait "$SLURMD_PID" 2>/dev/null || true
    [ -n "$CTLD_PID" ] && wait "$CTLD_PID" 2>/dev/null || true
    if [ "$status" != 0 ] && [ "$status" != 77 ]; then
        echo "--- logs"
        tail -n 30 "$TMP"/log/*.log "$TMP"/cluster/slurm/*.log 2>/dev/null || true
    fi
    rm -rf "$TMP"
    exit "$status"
}
trap cleanup EXIT

mkdir -p "$TMP/state" "$TMP/spool" "$TMP/log"
export SLURM_CONF="$TMP/slurm.conf"
CPUS=2
cat >"$SLURM_CONF" <<EOF
ClusterName=trnewsci
SlurmctldHost=localhost(127.0.0.1)
SlurmUser=root
SlurmdUser=root
AuthType=auth/none
CredType=cred/none
CommunicationParameters=NoCtldInAddrAny,NoInAddrAny
SlurmctldPort=6817
SlurmdPort=6818
StateSaveLocation=$TMP/state
SlurmdSpoolDir=$TMP/spool
SlurmctldPidFile=$TMP/slurmctld.pid
SlurmdPidFile=$TMP/slurmd.pid
SlurmctldLogFile=$TMP/log/slurmctld.log
SlurmdLogFile=$TMP/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/filetxt
JobCompLoc=$TMP/jobcomp.txt
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
MinJobAge=300
NodeName=localhost NodeAddr=127.0.0.1 CPUs=$CPUS RealMemory=1000 State=UNKNOWN
PartitionName=debug Nodes=localhost Default=YES MaxTime=INFINITE State=UP
EOF

slurmctld -D -c -f "$SLURM_CONF" >"$TMP/log/slurmctld.out" 2>&1 &
CTLD_PID=$!
slurmd -D -N localhost -f "$SLURM_CONF" >"$TMP/log/slurmd.out" 2>&1 &
SLURMD_PID=$!

wait_for() { # SECONDS DESCRIPTION COMMAND...: polls COMMAND every 0.5 s
    local limit=$1 what=$2
    shift 2
    local end=$((SECONDS + limit))
    until "$@"; do
        if [ "$SECONDS" -ge "$end" ]; then
            echo "FAILED: $what within $limit s"
            exit 1
        fi
        sleep 0.5
    done
}
node_idle() { [ "$(sinfo -h -o %T 2>/dev/null)" = idle ]; }
wait_for 60 "the node to come up idle" node_idle
echo "cluster up: $(sinfo -h -o '%P %D %T %c CPUs')"

# The reference: the same sweep run locally in one piece.
"$BIN" "$SCRIPT" --set resolution=smoke --quiet --out "$TMP/local" 2>"$TMP/local.err"

start=$SECONDS
"$BIN" slurm "$SCRIPT" --array 4 --cpus 1 --time 10:00 --set resolution=smoke \
    --out "$TMP/cluster" --submit | tee "$TMP/submit.out"
queue_empty() { [ -z "$(squeue -h 2>/dev/null)" ]; }
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
