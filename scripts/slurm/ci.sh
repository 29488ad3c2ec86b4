#!/usr/bin/env bash
# CI's test of the Slurm pipeline (issue 27), as root on Debian: starts a one-node Slurm
# cluster on this machine (local-cluster.sh), submits a 4-shard `pt` render of a small fig5
# through submit.sh, requeues one array task mid-render with `scontrol requeue` (it resumes
# from its checkpoint), and checks that the merged image equals the render on one machine
# bit for bit, and that a truncated shard is refused by the merge; then a method that learns
# (pg) through its learn job, an array of shards rendering with the plan and the merge, which
# must equal pg's render on one machine bit for bit; and ga-pt with its GA split over two
# learn jobs per wave, whose merged image must equal its render on one machine bit for bit;
# and a pg reference (both halves learned once), whose merge must equal the reference on one
# machine, its noise estimate included.
# Stops the daemons it started, whatever happens.
#
#   bash scripts/slurm/ci.sh [GENPATH]   # GENPATH: a built binary [target/release/genpath]
set -euo pipefail
repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
genpath=${1:-$repo/target/release/genpath}
[[ -x $genpath ]] || { echo "ci.sh: build genpath first (cargo build --release)" >&2; exit 2; }
work=$(mktemp -d /tmp/genpath-slurm-ci.XXXXXX)
export GENPATH_SLURM_DIR=$work/cluster
trap 'bash "$repo/scripts/slurm/local-cluster.sh" stop || true; rm -rf "$work" || true' EXIT
# A copy, so that a build during the run cannot change the binary under the tasks (their
# shards would then be of another build, which a resume and a merge rightly refuse).
cp "$genpath" "$work/genpath"
genpath=$work/genpath
bash "$repo/scripts/slurm/local-cluster.sh" start
export SLURM_CONF=$GENPATH_SLURM_DIR/slurm.conf

scene=$repo/scenes/fig5/scene.toml
flags=(--method pt --width 64 --height 64 --spp 4096 --seed 3)
# wait_for JOB: until the job has completed (at most 300 s); fails on any other end.
wait_for() {
    local i state=""
    for ((i = 0; i < 300; i++)); do
        state=$(scontrol show job "$1" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
        case $state in
        COMPLETED) return ;;
        FAILED | CANCELLED | TIMEOUT | OUT_OF_MEMORY | NODE_FAIL) fail "job $1: $state" ;;
        esac
        sleep 1
    done
    fail "job $1 did not complete within 300 s (state ${state:-unknown})"
}
fail() { echo "ci.sh: FAILED: $*" >&2; for f in "$work"/out*/slurm-*.out; do [[ -f $f ]] && { echo "--- $f" >&2; cat "$f" >&2; }; done; exit 1; }

echo "== the render on one machine"
"$genpath" render "$scene" "${flags[@]}" --quiet -o "$work/single.exr"

echo "== the pipeline: 4 shards and a merge"
submitted_at=$SECONDS
submitted=$(bash "$repo/scripts/slurm/submit.sh" --shards 4 --checkpoint 0.2 --genpath "$genpath" \
    "$scene" "$work/out" -- "${flags[@]}")
echo "$submitted"
array=$(sed -n 's/^shards: job \([0-9]*\) .*/\1/p' <<<"$submitted")
merge=$(sed -n 's/.*merge: job \([0-9]*\) .*/\1/p' <<<"$submitted")
[[ -n $array && -n $merge ]] || fail "no job ids in: $submitted"

echo "== requeue task 1 once it has written a checkpoint"
for ((i = 0; i < 600; i++)); do
    [[ -f $work/out/part-1.exr.shard ]] && break
    sleep 0.1
done
[[ -f $work/out/part-1.exr.shard ]] || fail "task 1 wrote no checkpoint within 60 s"
[[ -f $work/out/part-1.exr ]] && fail "task 1 finished before it could be requeued"
scontrol requeue "${array}_1"
# Slurm holds a requeued job back for a while (about 2 minutes here); let it run now.
for ((i = 0; i < 100; i++)); do
    scontrol show job "${array}_1" | grep -q "JobState=PENDING" && break
    sleep 0.1
done
scontrol update JobId="${array}_1" StartTime=now || true

echo "== wait for the merge (at most 300 s)"
wait_for "$merge"
restarts=$(scontrol show job "${array}_1" | sed -n 's/.*Restarts=\([0-9]*\).*/\1/p')
((restarts >= 1)) || fail "task 1 was not requeued (Restarts=${restarts:-?})"
grep -q "resuming from" "$work"/out/slurm-"${array}"_1.out || fail "task 1 did not resume from its shard file"
echo "task 1 ran $((restarts + 1)) times and resumed from its shard file; the pipeline took $((SECONDS - submitted_at)) s"
scontrol show job "${array}_1" | grep -o "SubmitTime=[^ ]*\|EligibleTime=[^ ]*\|StartTime=[^ ]*\|EndTime=[^ ]*" | tr "\n" " "; echo

echo "== the merged image is the render on one machine"
"$genpath" compare --bits "$work/out/merged.exr" "$work/single.exr" || fail "merged ≠ single"

echo "== a truncated shard is refused"
head -c -100 "$work/out/part-2.exr.shard" >"$work/part-2-cut.shard"
if "$genpath" merge "$work"/out/part-{0,1,3}.exr.shard "$work/part-2-cut.shard" -o "$work/bad.exr" 2>"$work/bad.err"; then
    fail "a truncated shard was merged"
fi
grep -q "truncated" "$work/bad.err" || fail "the refusal does not say truncated: $(cat "$work/bad.err")"
[[ -e $work/bad.exr ]] && fail "a refused merge wrote an image"
cat "$work/bad.err"
echo "== a method that learns: learn → array of 2 shards → merge (pg)"
pg=(--method pg --width 48 --height 40 --spp 64 --seed 5)
"$genpath" render "$scene" "${pg[@]}" --quiet -o "$work/single-pg.exr"
submitted=$(bash "$repo/scripts/slurm/submit.sh" --shards 2 --genpath "$genpath" \
    "$scene" "$work/out-pg" -- "${pg[@]}")
echo "$submitted"
grep -q "^learn: job" <<<"$submitted" || fail "no learn job for pg: $submitted"
merge=$(sed -n 's/.*merge: job \([0-9]*\) .*/\1/p' <<<"$submitted")
wait_for "$merge"
"$genpath" compare --bits "$work/out-pg/merged.exr" "$work/single-pg.exr" || fail "pg: merged ≠ single"

echo "== the GA split over learn jobs: 4 waves × 2 shards → learn → array of 2 shards → merge (ga-pt)"
gapt=(--method ga-pt --width 48 --height 40 --spp 16 --seed 7 --spatial-passes 2
    --ga-grid 16 --test-paths 3000 --population 12 --generations 6)
"$genpath" render "$scene" "${gapt[@]}" --quiet -o "$work/single-ga-pt.exr"
submitted=$(bash "$repo/scripts/slurm/submit.sh" --shards 2 --learn-shards 2 --genpath "$genpath" \
    "$scene" "$work/out-ga-pt" -- "${gapt[@]}")
echo "$submitted"
grep -q "^learn: waves: jobs" <<<"$submitted" || fail "the GA was not split: $submitted"
merge=$(sed -n 's/.*merge: job \([0-9]*\) .*/\1/p' <<<"$submitted")
wait_for "$merge"
ls "$work/out-ga-pt/plan.bin.learning"
ls "$work/out-ga-pt/plan.bin.learning" | grep -q "wave-0.1-of-2.bin" || fail "no pilot wave of shard 1/2"
"$genpath" compare --bits "$work/out-ga-pt/merged.exr" "$work/single-ga-pt.exr" || fail "ga-pt: merged ≠ single"
echo "== a reference of a method that learns: learn both halves → array of 2 shards → merge (pg)"
"$genpath" reference "$scene" "${pg[@]}" --quiet -o "$work/single-ref.exr"
submitted=$(bash "$repo/scripts/slurm/submit.sh" --reference --shards 2 --genpath "$genpath" \
    "$scene" "$work/out-ref" -- "${pg[@]}")
echo "$submitted"
grep -q "^learn: job" <<<"$submitted" || fail "no learn job for the pg reference: $submitted"
merge=$(sed -n 's/.*merge: job \([0-9]*\) .*/\1/p' <<<"$submitted")
wait_for "$merge"
"$genpath" compare --bits "$work/out-ref/merged.exr" "$work/single-ref.exr" || fail "reference: merged ≠ single"
# The noise estimate of the two halves, as the reference on one machine wrote it.
estimate() { python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["reference"])' "$1"; }
[[ "$(estimate "$work/out-ref/merged.exr.json")" == "$(estimate "$work/single-ref.exr.json")" ]] ||
    fail "reference: the merged noise estimate differs: $(estimate "$work/out-ref/merged.exr.json")"
echo "Slurm pipeline: ok"
