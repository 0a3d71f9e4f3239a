# A one-node Slurm cluster on this machine, for tests/slurm/run.sh and tests/slurm/on_cluster.sh
# (sourced, not run): Debian's slurmctld, slurmd and slurm-client (installed with apt-get when
# missing), auth/none, every daemon listening on 127.0.0.1 only, state in a temporary
# directory $TMP, started in the foreground as children of the sourcing script and stopped by
# their process ids on exit. No accounting database: job states come from the job completion
# file $TMP/jobcomp.txt. Exits 77 (skipped) when Slurm is missing and cannot be installed.
# After sourcing: SLURM_CONF is exported, the node is idle, wait_for and queue_empty are
# defined.

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
queue_empty() { [ -z "$(squeue -h 2>/dev/null)" ]; }
wait_for 60 "the node to come up idle" node_idle
echo "cluster up: $(sinfo -h -o '%P %D %T %c CPUs')"

