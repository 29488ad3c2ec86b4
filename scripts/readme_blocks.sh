#!/usr/bin/env bash
# Runs the README's code blocks as a reader would, so that they cannot drift from the code:
# every ```sh block of README.md, as one bash script per block (`set -euo pipefail`), in a
# scratch directory that links the repository's top-level entries (so `scenes/…`,
# `reports/refs/…` and `target/release/genpath` resolve and the outputs land in the scratch
# directory), with target/release first on PATH (`genpath` is target/release/genpath).
#
# Two lines are left out, since CI runs them in steps of their own (.ci/run: the quickstart,
# and README_TEST_CMD, which check_readme_command keeps identical to the README's):
#   bash scripts/quickstart.sh
#   cargo test --profile release-tests --workspace --all-features
#
# Usage: bash scripts/readme_blocks.sh [README.md]. It builds genpath in release mode first
# (nothing to do after the quickstart, which CI runs before it), so that the blocks run the
# code as it is. Exits non-zero if a block fails or if the file has no block left to run.
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)
readme=$(realpath "${1:-$repo/README.md}")
skip=("bash scripts/quickstart.sh" "cargo test --profile release-tests --workspace --all-features")

export PATH="$HOME/.cargo/bin:$PATH"
cargo build --release --manifest-path "$repo/Cargo.toml"
export PATH="$repo/target/release:$PATH"

work=$(mktemp -d /tmp/genpath-readme.XXXXXX)
trap 'rm -rf "$work"' EXIT
for entry in "$repo"/*; do
    ln -s "$entry" "$work/$(basename "$entry")"
done

# One file per block: block-1.sh, block-2.sh, … (skipped lines become comments, so that a
# block's line numbers stay the README's order).
awk -v dir="$work" -v skip1="${skip[0]}" -v skip2="${skip[1]}" '
    /^```sh[[:space:]]*$/ { n++; file = dir "/block-" n ".sh"; inblock = 1; next }
    /^```/ && inblock { inblock = 0; close(file); next }
    inblock {
        line = $0; sub(/[[:space:]]+$/, "", line)
        if (line == skip1 || line == skip2) line = "# (run by CI in its own step) " line
        print line > file
    }' "$readme"

shopt -s nullglob
blocks=("$work"/block-*.sh)
((${#blocks[@]})) || { echo "readme_blocks: no \`\`\`sh block in $readme" >&2; exit 1; }
ran=0 failed=0
for ((i = 1; i <= ${#blocks[@]}; i++)); do
    b=$work/block-$i.sh
    if ! grep -qv '^[[:space:]]*\(#.*\)\?$' "$b"; then
        echo "==> block $i: nothing to run here (CI runs its commands)"
        continue
    fi
    echo "==> block $i of $readme:"
    sed 's/^/    /' "$b"
    start=$SECONDS
    if (cd "$work" && bash -euo pipefail "$b"); then
        echo "<== block $i: ok in $((SECONDS - start)) s"
    else
        echo "<== block $i: FAILED (status $?) after $((SECONDS - start)) s" >&2
        failed=1
    fi
    ran=$((ran + 1))
done
((ran)) || { echo "readme_blocks: every block was left out: nothing checked" >&2; exit 1; }
exit "$failed"
