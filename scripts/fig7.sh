#!/usr/bin/env bash
# Paper Fig. 7 on fig5: relMSE against paths per pixel for srt, pt and ga, and ga for several
# test-path counts M. Usage: scripts/fig7.sh REFERENCE.exr [OUTDIR]
# Prints a Markdown table (method, M, spp, GA seconds, render seconds, relMSE). srt and ga
# use the paper's estimator, next-event estimation at the path's end only (--nee end); NEE=every
# gives the same table for next-event estimation at every vertex.
set -euo pipefail
ref=${1:?usage: scripts/fig7.sh REFERENCE.exr [OUTDIR]}
out=${2:-fig7-out}
bin=${GENPATH:-target/release/genpath}
scene=scenes/fig5/scene.toml
nee=${NEE:-end}
mkdir -p "$out"
echo "| method | M | spp | GA s | render s | relMSE |"
echo "|---|---|---|---|---|---|"
row() { # method M spp file
  local json="$4.json"
  local rel; rel=$("$bin" compare "$4" "$ref" --json | python3 -c 'import json,sys; print("%.4g" % json.load(sys.stdin)["relmse"])')
  python3 - "$json" "$1" "$2" "$3" "$rel" <<'PY'
import json, sys
d = json.load(open(sys.argv[1])); t = d["times_s"]
print(f"| {sys.argv[2]} | {sys.argv[3]} | {sys.argv[4]} | {t.get('ga') or 0:.2f} | {t['render']:.2f} | {sys.argv[5]} |")
PY
}
for spp in 16 64 256; do
  for m in pt srt; do
    "$bin" render "$scene" --method $m --nee "$nee" --spp $spp --max-bounces 5 -q -o "$out/$m-$spp.exr"
    row $m - $spp "$out/$m-$spp.exr"
  done
done
for M in 100 1000 10000; do
  for spp in 16 64 256; do
    # Every sample from the GA's mixtures (none of the plan's baseline `srt` samples, and
    # without the gate, which would send pixels to `pt`): the figure compares the paper's
    # estimators at equal paths.
    "$bin" render "$scene" --method ga --no-gate --nee "$nee" --test-paths $M --spp $spp \
        --max-bounces 5 --baseline-keep-ratio 0 -q -o "$out/ga-$M-$spp.exr"
    row ga $M $spp "$out/ga-$M-$spp.exr"
  done
done
# The default M, once.
"$bin" render "$scene" --method ga --no-gate --nee "$nee" --spp 64 --max-bounces 5 \
    --baseline-keep-ratio 0 -q -o "$out/ga-default-64.exr"
row ga default 64 "$out/ga-default-64.exr"
