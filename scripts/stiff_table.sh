#!/usr/bin/env bash
# The stiff catalogue as a table: per scene and method, bad pixels, the densities seen
# (from `genpath check`) and relMSE against a long pt reference, at 32×32. The renders use
# seed 7, the reference seed 1: disjoint random streams.
#   bash scripts/stiff_table.sh [REF_SPP (65536)] [SPP (1024)]
set -euo pipefail
bin=${GENPATH:-target/release/genpath}
ref_spp=${1:-65536}
spp=${2:-1024}
out=${OUT:-stiff-out}
mkdir -p "$out"
echo "| scene | method | bad pixels | min pdf | max pdf | relMSE vs reference | reference's own relMSE |"
echo "|---|---|---|---|---|---|---|"
for dir in scenes/stiff/*/; do
    name=$(basename "$dir")
    size=(--width 32 --height 32 --quiet)
    "$bin" reference "$dir/scene.toml" "${size[@]}" --spp "$ref_spp" -o "$out/$name-ref.exr"
    "$bin" check "$dir/scene.toml" "${size[@]}" --spp 64 --json "$out/$name-check.json" > /dev/null || true
    for method in pt srt ga ga-pt; do
        "$bin" render "$dir/scene.toml" "${size[@]}" --method "$method" --spp "$spp" \
            --ga-grid 8 --test-paths 10000 --seed 7 -o "$out/$name-$method.exr"
        rel=$("$bin" compare "$out/$name-$method.exr" "$out/$name-ref.exr" --json)
        python3 - "$out/$name-check.json" "$out/$name-ref.exr.json" "$name" "$method" "$rel" <<'PY'
import json, sys
check = json.load(open(sys.argv[1])); ref = json.load(open(sys.argv[2]))
name, method, rel = sys.argv[3], sys.argv[4], json.loads(sys.argv[5])
key = method
m = next(m for m in check["methods"] if m["method"] == key)
print(f"| {name} | {method} | {m['bad_pixels']} | {check['pdf_min']:.2e} | {check['pdf_max']:.2e} | "
      f"{rel['relmse']:.3e} | {ref['reference']['relmse_estimate']:.1e} |")
PY
    done
done
