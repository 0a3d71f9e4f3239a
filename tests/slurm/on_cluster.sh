#!/usr/bin/env bash
# Runs an experiment script as a Slurm job array plus its merge on a one-node cluster on this
# machine (tests/slurm/cluster.sh): a full-size sweep through Slurm, as on a cluster.
#
# Usage: tests/slurm/on_cluster.sh TRNEWS_SCRIPT_BINARY OUT_DIR SCRIPT SLURM_OPTIONS...
#   e.g. tests/slurm/on_cluster.sh target/release/trnews-script out/scan scripts/scan.rhai \
#            --array 2 --cpus 1 --time 2:00:00 --set crack_x_mm=10
#
# `trnews-script slurm` writes and submits the array and the merge (docs/src/guide/sweeps.md);
# this waits for both and prints their job states. The figures and tables are in
# OUT_DIR/plots, each task's log (with every point's run report) in OUT_DIR/slurm. Exit
# status: 0 every job completed, 77 Slurm is missing and cannot be installed, else failed.
set -euo pipefail

BIN=$(realpath "${1:?usage: $0 TRNEWS_SCRIPT_BINARY OUT_DIR SCRIPT SLURM_OPTIONS...}")
OUT=$(realpath -m "${2:?usage: $0 TRNEWS_SCRIPT_BINARY OUT_DIR SCRIPT SLURM_OPTIONS...}")
shift 2

# shellcheck source=tests/slurm/cluster.sh
source "$(dirname "$0")/cluster.sh"

start=$SECONDS
"$BIN" slurm "$@" --out "$OUT" --submit
wait_for 86400 "the array and merge jobs to finish" queue_empty
echo "array + merge finished in $((SECONDS - start)) s"
# the completion file lags the queue slightly
sleep 2
grep -o ' Name=[^ ]* JobState=[^ ]*' "$TMP/jobcomp.txt" | sort | uniq -c
if grep 'JobState=' "$TMP/jobcomp.txt" | grep -v 'JobState=COMPLETED' >/dev/null; then
    echo "FAILED: not every job completed"
    exit 1
fi
