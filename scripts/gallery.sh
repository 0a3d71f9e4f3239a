#!/usr/bin/env bash
# Rebuilds the committed gallery: the figures and tables under plots/ that
# docs/src/figures.md shows, and the L-bracket's (docs/src/guide/meshes.md), on the default
# (quick) scene, with error estimates where the experiment has them. About 2 hours on 2
# cores. Other runs write under out/ (git-ignored); this one writes into the
# checkout (`--out .`), so `git diff plots/` shows what changed.
#
#   scripts/gallery.sh            # every figure
#   scripts/gallery.sh spectra    # only the scripts named (file stems)
#
# Not part of it, each for hours: the accuracy study behind the presets
# (scripts/sem_target.rhai, in pieces: docs/src/validation/default-experiment.md), the scans
# (scripts/scans.sh) and the resonance-tuned trains (docs/src/guide/scan.md), and the
# experiments rerun with losses (docs/src/figures.md, "Which findings survive realistic
# losses").
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
    [losses]=""
    [bracket]=""
)
order=(sweep_delays trnews_focus pulse_inversion spectra convergence work_precision stability losses bracket)
chosen=("${@:-${order[@]}}")
for name in "${chosen[@]}"; do
    if [[ -z "${args[$name]+set}" ]]; then
        echo "gallery: no gallery script '$name' (one of: ${order[*]})" >&2
        exit 2
    fi
    # shellcheck disable=SC2086 # the arguments are words
    target/release/trnews-script "scripts/$name.rhai" --out . ${args[$name]}
done
