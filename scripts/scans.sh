#!/usr/bin/env bash
# Remakes the committed scans of docs/src/guide/scan.md: each placement's scan (its maps and
# localisation, plots/scan_RES_NAME*.csv), then the crack located from both sides from each
# mirror pair (plots/scan_sides_quick_NAME.{csv,png}). Each scan runs in out/scans/NAME, its
# positions stored there as they finish, so a scan cut short resumes where it stopped. On
# the 2-core AMD EPYC machine a 41-position quick scan took 34-49 min (2026-12-02), a
# 21-position one 13-16 min (2026-11-27); the smoke ones take minutes.
#
#   scripts/scans.sh                 # every scan, then every both-sides table
#   scripts/scans.sh x5 x11          # only the scans named
#   scripts/scans.sh sides           # only the both-sides tables, from the committed scans
#
# Not part of scripts/gallery.sh: the scans take longer than the rest of the gallery together.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet

# name: the scan's arguments (the crack's placement and the positions); the resolution is
# the name's prefix (smoke_...) or quick.
declare -A args=(
    [default]=""
    [x5]="--set crack_x_mm=5"
    [x11]="--set crack_x_mm=11"
    [x6_l3]="--set crack_x_mm=6 --set crack_length_mm=3 --set positions=21 --set from_mm=2.5 --set to_mm=9.5"
    [x10_l3]="--set crack_x_mm=10 --set crack_length_mm=3 --set positions=21 --set from_mm=6.5 --set to_mm=13.5"
    [d293]="--set crack_depth_mm=2.93 --set positions=21 --set from_mm=4.5 --set to_mm=11.5"
    [a_x475]="--set crack_x_mm=4.75 --set crack_length_mm=2.5 --set crack_depth_mm=2.45 --set positions=21 --set from_mm=1.25 --set to_mm=8.25"
    [a_x1125]="--set crack_x_mm=11.25 --set crack_length_mm=2.5 --set crack_depth_mm=2.45 --set positions=21 --set from_mm=7.75 --set to_mm=14.75"
    [b_x625]="--set crack_x_mm=6.25 --set crack_length_mm=1.5 --set crack_depth_mm=1.47 --set positions=21 --set from_mm=2.75 --set to_mm=9.75"
    [b_x975]="--set crack_x_mm=9.75 --set crack_length_mm=1.5 --set crack_depth_mm=1.47 --set positions=21 --set from_mm=6.25 --set to_mm=13.25"
    [survey_x5]="--set focus=false --set crack_x_mm=5"
    [survey_x10_l3]="--set focus=false --set crack_x_mm=10 --set crack_length_mm=3"
    [survey_d293]="--set focus=false --set crack_depth_mm=2.93"
    [smoke]="--set resolution=smoke"
    [smoke_41]="--set resolution=smoke --set positions=41"
    [smoke_x2]="--set resolution=smoke --set positions=41 --set crack_x_mm=2"
    [smoke_x35_l2]="--set resolution=smoke --set positions=41 --set crack_x_mm=3.5 --set crack_length_mm=2"
    [smoke_d15]="--set resolution=smoke --set positions=41 --set crack_depth_mm=1.5"
)
order=(default x5 x11 x6_l3 x10_l3 d293 a_x475 a_x1125 b_x625 b_x975
    survey_x5 survey_x10_l3 survey_d293 smoke smoke_41 smoke_x2 smoke_x35_l2 smoke_d15)
# Both-sides tables: the scan and its mirror placement's scan, read mirrored as the left view
# (a centred placement is its own mirror).
declare -A mirror=(
    [default]=default [x5]=x11 [x11]=x5 [x6_l3]=x10_l3 [x10_l3]=x6_l3 [d293]=d293
    [a_x475]=a_x1125 [a_x1125]=a_x475 [b_x625]=b_x975 [b_x975]=b_x625
)

# plots/ name of scan NAME's table: scan_quick_x5, scan_quick (default), scan_smoke_x2, ...
table() {
    case "$1" in
        default) echo scan_quick ;;
        smoke) echo scan_smoke ;;
        smoke_*) echo "scan_smoke_${1#smoke_}" ;;
        *) echo "scan_quick_$1" ;;
    esac
}

# Copies $1 to $2 whole: into a temporary name beside $2, then renamed over it.
copy_whole() {
    cp "$1" "$2.tmp.$$"
    mv -f "$2.tmp.$$" "$2"
}

scan() {
    local name=$1 dir="out/scans/$1" to
    to=$(table "$name")
    # shellcheck disable=SC2086 # the arguments are words
    target/release/trnews-script scripts/scan.rhai --out "$dir" --data "$dir" ${args[$name]}
    copy_whole "$dir/plots/scan.csv" "plots/$to.csv"
    copy_whole "$dir/plots/scan_localisation.csv" "plots/${to}_localisation.csv"
    case "$name" in default | smoke) copy_whole "$dir/plots/scan.png" "plots/$to.png" ;; esac
}

sides() {
    local name=$1 right left suffix
    right="plots/$(table "$name").csv"
    left="plots/$(table "${mirror[$name]}").csv"
    suffix=${name/#default/}
    target/release/trnews-script scripts/scan_sides.rhai --out . --data . \
        --set right="$right" --set left="$left" --set left_mirrored=true \
        --set name="scan_sides_quick${suffix:+_$suffix}"
}

if (($#)); then chosen=("$@"); else chosen=("${order[@]}" sides); fi
# Every name is checked before any scan runs: a misspelt last name must not wait for hours.
for name in "${chosen[@]}"; do
    if [[ "$name" != sides && -z "${args[$name]+set}" ]]; then
        echo "scans: no scan '$name' (one of: ${order[*]} sides)" >&2
        exit 2
    fi
done
for name in "${chosen[@]}"; do
    if [[ "$name" == sides ]]; then
        for n in "${!mirror[@]}"; do sides "$n"; done
    else
        scan "$name"
    fi
done
