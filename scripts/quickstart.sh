#!/usr/bin/env bash
# Installs what is missing (scripts/setup.sh), builds genpath in release mode and renders the
# default scene (the paper's Fig. 5) with genetic path generation (--method ga, the paper's
# method everywhere: --no-gate, see the README) to fig5.exr and fig5.png in the current
# directory, with fig5-explain.png showing what the GA learned.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$here/scripts/setup.sh"
export PATH="$HOME/.cargo/bin:$PATH"
cargo run --release --manifest-path "$here/Cargo.toml" -- \
    render "$here/scenes/fig5/scene.toml" --method ga --no-gate -o fig5.exr -o fig5.png \
    --explain fig5-explain.png "$@"
