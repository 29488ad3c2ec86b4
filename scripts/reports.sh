#!/usr/bin/env bash
# Regenerates reports/: for each scene, relMSE against wall-clock time (every phase included)
# for pt, srt and GA variants, at 256×256 and max bounces 5, against the committed references
# in reports/refs/ (made with `genpath reference … --spp 16384/8192`, see reports/README.md).
#
#   bash scripts/reports.sh [BUDGETS]        # default BUDGETS: 2,8,30 (seconds)
#
# The default GA runs on fig5 only (see below). SCENES="fig1 cbox" limits the scenes.
# Seeds 101, 102, …: disjoint from the references' streams (their seed 1 was used before
# `genpath reference` derived its halves' seeds).
# Writes reports/SCENE.csv, reports/SCENE.svg and reports/SCENE.md (the table behind the plot)
# and reports/bench.json (`genpath bench`). Takes about 4 × 5 × (sum of budgets) seconds.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$here"
budgets=${1:-2,8,30}
cargo build --release --features obvhs
bin=${GENPATH:-target/release/genpath}
cheap=m=10000:pop=30:gen=20:grid=32
for scene in ${SCENES:-fig5 fig1 cbox glossy}; do
    # The default GA (60 × 50, M = 50 000, grid 16) takes 34 s on fig5 and many minutes where
    # more test paths carry light (fig1, cbox, glossy): there only the cheap variant runs.
    case $scene in
        fig5) methods="pt,srt,ga,ga:$cheap,ga-pt:$cheap" ;;
        *) methods="pt,srt,ga:$cheap,ga-pt:$cheap" ;;
    esac
    "$bin" sweep "scenes/$scene/scene.toml" --ref "reports/refs/${scene}_ref.exr" \
        --time --budgets "$budgets" --methods "$methods" --max-bounces 5 --quiet --seed 101 \
        -o "reports/$scene" > "reports/$scene.md"
    echo "reports/$scene: done"
done
"$bin" bench scenes/cbox/scene.toml --json reports/bench.json > reports/bench.txt
"$bin" bench scenes/fig5/scene.toml --json reports/bench-fig5.json > reports/bench-fig5.txt
