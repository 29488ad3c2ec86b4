#!/usr/bin/env bash
# Instructions executed by a render, counted by valgrind (cachegrind, no cache simulation):
# a speed comparison of two builds that other work on a shared machine cannot disturb.
#
#   bash scripts/icount.sh BASE_BIN NEW_BIN [RENDER ARGS…]
#
# Renders every method of scripts/bitcheck.sh on each scene of SCENES (fig5 cbox) at SIZE²
# (96), SPP (16) and SEED (7), on one thread, with both binaries, and prints the whole
# process's instruction counts (start-up and image output included) and their ratio
# (new / base). Needs Debian's `valgrind`. Slow: about 50 × the native run.
set -euo pipefail
[[ $# -ge 2 ]] || { echo "usage: bash scripts/icount.sh BASE_BIN NEW_BIN [RENDER ARGS…]" >&2; exit 2; }
base=$1 new=$2
shift 2
cd "$(dirname "${BASH_SOURCE[0]}")/.."
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
methods=("pt" "srt" "ga" "ga-pt" "ga-pt --spatial-guide false" "pg" "ga --no-gate" "ga-pt --no-gate")
for scene in ${SCENES:-fig5 cbox}; do
    variants=("${methods[@]}")
    [[ -f scenes/$scene/anchors.toml ]] && variants+=("mixture --generators scenes/$scene/anchors.toml")
    for m in "${variants[@]}"; do
        read -ra margs <<<"$m"
        declare -A count=()
        for side in base new; do
            bin=$base
            [[ $side == new ]] && bin=$new
            valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null \
                "$bin" render "scenes/$scene/scene.toml" --method "${margs[@]}" \
                --spp "${SPP:-16}" --seed "${SEED:-7}" --width "${SIZE:-96}" --height "${SIZE:-96}" \
                --threads 1 --quiet -o "$out/$side.exr" "$@" 2>"$out/log"
            count[$side]=$(grep -oP 'I\s+refs:\s+\K[\d,]+' "$out/log" | tr -d ,)
        done
        printf 'icount %-6s %-48s base %14d  new %14d  ratio %.4f\n' "$scene" "$m" \
            "${count[base]}" "${count[new]}" "$(echo "${count[new]} / ${count[base]}" | bc -l)"
        unset count
    done
done
