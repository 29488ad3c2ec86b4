#!/usr/bin/env bash
# Bit-identity check: renders every method on every scene with a build of BASE and with a
# build of this checkout (or of the commit NEW), and compares the images byte for byte.
#
#   bash scripts/bitcheck.sh BASE [NEW]     # e.g. bash scripts/bitcheck.sh 220537e
#
# BASE (and NEW, when given) are built from git worktrees under target/bitcheck/, with a
# target directory of their own there (kept between runs, so a second run only rebuilds
# genpath itself). Without NEW the working tree is built as it is, uncommitted changes
# included. SCENES (names or scene files), SPP (16), SEED (7), SIZE (the image's width and
# height; default the scene's) and FEATURES (the default features) may be set in
# the environment, and BASE_BIN (NEW_BIN), a binary already built from BASE (NEW or the working
# tree), saves building it. NEW_ARGS are given to the new build's renders only (a setting
# that selects what BASE did where a later default differs, e.g. `--nee end`).
# With TIMES=N (N odd, e.g. 5) each render is also timed N times per build, the two builds
# alternating, and the median wall-clock seconds of the whole process are printed with
# their ratio (new / base); with CLOCK=cpu, the CPU seconds (user + system) instead, which
# other work on a shared machine disturbs less. Writes the images to target/bitcheck/out/{base,new}/ and prints one line
# per render; exits 1 if any image's pixels differ in their bits (with its relMSE against
# BASE's), 0 otherwise.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
[[ $# -ge 1 && $# -le 2 ]] || { echo "usage: bash scripts/bitcheck.sh BASE [NEW]" >&2; exit 2; }
scenes=${SCENES:-fig5 fig1 cbox glossy}
spp=${SPP:-16}
seed=${SEED:-7}
features=(${FEATURES:+--features "$FEATURES"})
work=$here/target/bitcheck
mkdir -p "$work"

# build COMMIT NAME: builds COMMIT in worktree NAME; prints the binary's path.
build() {
    local commit=$1 name=$2 tree=$work/tree-$2
    git rev-parse --verify -q "$commit^{commit}" >/dev/null ||
        { echo "bitcheck: $commit is not a commit" >&2; return 1; }
    if [[ -d $tree ]]; then
        git -C "$tree" checkout -q --detach "$commit"
    else
        git worktree add -q --detach "$tree" "$commit"
    fi
    (cd "$tree" && cargo build -q --release "${features[@]}" --target-dir "$work/target-$name" >&2)
    echo "$work/target-$name/release/genpath"
}

if [[ -n ${BASE_BIN:-} ]]; then
    base_bin=$BASE_BIN # a binary already built from BASE
else
    base_bin=$(build "$1" base)
fi
if [[ -n ${NEW_BIN:-} ]]; then
    new_bin=$NEW_BIN # a binary already built from NEW (or the working tree)
elif [[ $# -eq 2 ]]; then
    new_bin=$(build "$2" new)
else
    cargo build -q --release "${features[@]}" >&2
    new_bin=${CARGO_TARGET_DIR:-$here/target}/release/genpath
fi
echo "bitcheck: base $(git rev-parse --short "$1") against ${2:-the working tree}; $spp spp, seed $seed"

# Every method, with the variants a flag selects. `mixture` renders the scene's anchors.toml
# where it has one.
methods=("pt" "srt" "ga" "ga-pt" "ga-pt --spatial-guide false" "pg" "ga --no-gate" "ga-pt --no-gate")
rm -rf "$work/out"
mkdir -p "$work/out/base" "$work/out/new"
differ=0 count=0
for scene in $scenes; do
    # A scene name (scenes/NAME/scene.toml) or a scene file's path (TOML or Mitsuba XML).
    file=scenes/$scene/scene.toml
    [[ $scene == *.toml || $scene == *.xml ]] && file=$scene
    variants=("${methods[@]}")
    [[ -f $(dirname "$file")/anchors.toml ]] && variants+=("mixture --generators $(dirname "$file")/anchors.toml")
    for m in "${variants[@]}"; do
        read -ra margs <<<"$m"
        tag=$(tr '/' '_' <<<"${scene%.*}")-$(tr ' /' '__' <<<"$m" | tr -s '_' | sed 's/--//g')
        for side in base new; do
            bin=$base_bin
            [[ $side == new ]] && bin=$new_bin
            extra=()
            [[ $side == new ]] && read -ra extra <<<"${NEW_ARGS:-}"
            "$bin" render "$file" --method "${margs[@]}" --spp "$spp" --seed "$seed" --quiet \
                ${SIZE:+--width "$SIZE" --height "$SIZE"} -o "$work/out/$side/$tag.exr" "${extra[@]}"
        done
        count=$((count + 1))
        if ((${TIMES:-0} > 0)); then
            declare -A t=()
            for ((i = 0; i < TIMES; i++)); do
                for side in base new; do
                    bin=$base_bin
                    [[ $side == new ]] && bin=$new_bin
                    # Real, user and system seconds of the whole process.
                    times=$( { TIMEFORMAT='%3R %3U %3S'; time "$bin" render "$file" \
                        --method "${margs[@]}" --spp "$spp" --seed "$seed" --quiet \
                        -o "$work/out/$side/time.exr"; } 2>&1)
                    read -r real user sys <<<"$times"
                    if [[ ${CLOCK:-wall} == cpu ]]; then
                        t[$side]+="$(echo "$user + $sys" | bc) "
                    else
                        t[$side]+="$real "
                    fi
                done
            done
            median() { tr ' ' '\n' <<<"$1" | grep . | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
            mb=$(median "${t[base]}") mn=$(median "${t[new]}")
            printf 'time       %-48s base %6.3f s  new %6.3f s  ratio %.3f (%s)\n' "$tag" "$mb" "$mn" \
                "$(echo "$mn / $mb" | bc -l)" "${CLOCK:-wall}"
            unset t
        fi
        # Pixels bit for bit (the EXR's header holds the time it was written).
        if result=$("$new_bin" compare --bits "$work/out/new/$tag.exr" "$work/out/base/$tag.exr" 2>&1); then
            echo "identical  $tag"
        else
            differ=$((differ + 1))
            echo "DIFFERENT  $tag: $(tr '\n' ' ' <<<"$result")"
        fi
    done
done
echo "bitcheck: $((count - differ)) of $count renders bit-identical"
((differ == 0))
