#!/usr/bin/env bash
# Installs what is missing (scripts/setup.sh), builds genpath in release mode and renders the
# default scene (the paper's Fig. 5) for 8 seconds each, every phase counted, with path
# tracing (`pt`) and with the GA's best method (`ga-pt`, the default of `render`); writes
# fig5-compare.svg (the two renders, their per-pixel error against the committed reference,
# and the reference, labelled with relMSE and seconds) and fig5-sweep.csv / .svg in the
# current directory, and prints ga-pt's relMSE over pt's at equal time. Extra arguments go to
# `genpath sweep` (e.g. --budgets 30).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$here/scripts/setup.sh"
export PATH="$HOME/.cargo/bin:$PATH"
cargo run --release --manifest-path "$here/Cargo.toml" -- \
    sweep "$here/scenes/fig5/scene.toml" --ref "$here/reports/refs/fig5_ref.exr" \
    --methods pt,ga-pt --time --budgets 8 --picture fig5-compare.svg -o fig5-sweep "$@"
