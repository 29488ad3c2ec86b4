#!/usr/bin/env bash
# Installs what is missing (scripts/setup.sh), builds genpath in release mode and renders the
# default scene (the paper's Fig. 5) for 8 seconds each, every phase counted, with path
# tracing (`pt`), with path guiding (`pg`, the strongest method without the GA) and with the
# GA's best method (`ga-pt`, the default of `render`); writes fig5-compare.svg (the three
# renders, their per-pixel error against the committed reference, and the reference,
# labelled with relMSE and seconds) and fig5-sweep.csv / .svg in the current directory, and
# prints ga-pt's relMSE over pt's and over pg's at equal time. Extra arguments go to
# `genpath sweep` (e.g. --seed 2, --budgets 30).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$here/scripts/setup.sh"
export PATH="$HOME/.cargo/bin:$PATH"
cargo run --release --manifest-path "$here/Cargo.toml" -- \
    sweep "$here/scenes/fig5/scene.toml" --ref "$here/reports/refs/fig5_ref.exr" \
    --methods pt,pg,ga-pt --time --budgets 8 --picture fig5-compare.svg -o fig5-sweep "$@"
# The sweep prints each method against the first (pt); the line the README quotes puts the
# GA's method against both baselines, from the largest budget's first repetition in the table
# (relMSE × seconds, as the sweep's own ratios).
awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
    { m = $col["method"]; b = $col["budget"] + 0
      if (!(m in e) || b > budget[m]) { budget[m] = b; e[m] = $col["relmse"] * $col["seconds"]; r[m] = $col["relmse"]; s[m] = $col["seconds"] } }
    END {
        if (!("pt" in e) || !("pg" in e) || !("ga-pt" in e)) { print "quickstart: fig5-sweep.csv lacks pt, pg or ga-pt" > "/dev/stderr"; exit 1 }
        line = sprintf("ga-pt: relMSE %.3e in %.2f s: %.2f × pt'"'"'s and %.2f × pg'"'"'s at equal time", r["ga-pt"], s["ga-pt"], e["ga-pt"] / e["pt"], e["ga-pt"] / e["pg"])
        sub(/e-0/, "e-", line); sub(/e\+0/, "e", line)
        print line
    }' fig5-sweep.csv
