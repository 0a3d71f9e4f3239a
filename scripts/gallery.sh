#!/usr/bin/env bash
# Rebuilds the committed gallery: every figure and table under plots/ that the book shows,
# on the default (quick) scene, with error estimates where the experiment has them. About an
# hour on 2 cores. Other runs write under out/ (git-ignored); this one writes into the
# checkout (`--out .`), so `git diff plots/` shows what changed.
#
#   scripts/gallery.sh            # every figure
#   scripts/gallery.sh spectra    # only the scripts named (file stems)
#
# The accuracy study behind the presets (scripts/sem_target.rhai) is not part of it: it runs
# for hours, in pieces (see docs/src/validation/default-experiment.md).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet
declare -A args=(
    [sweep_delays]="--set error_estimate=true"
    [trnews_focus]="--set error_estimate=true"
    [pulse_inversion]="--set error_estimate=true"
    [spectra]="--set error_estimate=true"
    [convergence]=""
    [work_precision]=""
    [stability]=""
)
order=(sweep_delays trnews_focus pulse_inversion spectra convergence work_precision stability)
chosen=("${@:-${order[@]}}")
for name in "${chosen[@]}"; do
    if [[ -z "${args[$name]+set}" ]]; then
        echo "gallery: no gallery script '$name' (one of: ${order[*]})" >&2
        exit 2
    fi
    # shellcheck disable=SC2086 # the arguments are words
    target/release/trnews-script "scripts/$name.rhai" --out . ${args[$name]}
done
