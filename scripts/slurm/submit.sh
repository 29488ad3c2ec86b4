#!/usr/bin/env bash
# Submits one genpath render to Slurm as a job array of shards and a merge job:
#
#   bash scripts/slurm/submit.sh [OPTIONS] SCENE OUTDIR -- RENDER_FLAGS...
#
# e.g.  bash scripts/slurm/submit.sh --shards 16 --cpus 8 scenes/cbox/scene.toml runs/cbox \
#           -- --method pt --spp 65536
#
# Array task K renders `genpath render SCENE --shard K/N RENDER_FLAGS -o OUTDIR/part-K.exr`
# (scripts/slurm/shard.sbatch), writing a checkpoint every --checkpoint seconds; a task that
# Slurm stops (time limit, preemption, `scontrol requeue`) writes what it has, is requeued
# and resumes from its shard file. The merge job (scripts/slurm/merge.sbatch) runs when every
# task has succeeded (--dependency=afterok) and writes OUTDIR/merged.exr from the N shard
# files. Prints the two job ids.
#
# Options:
#   --shards N        shards (array tasks) [4]
#   --cpus C          CPUs per task, genpath's --threads [1]
#   --mem M           memory per task, as sbatch takes it [2G]
#   --time T          time limit per task run [01:00:00]
#   --checkpoint S    seconds between checkpoints [60]
#   --tasks LIST      only these array indices (e.g. 1,5-7): resubmits failed tasks, whose
#                     partial shard files they resume from, with a new merge job
#   --genpath PATH    the genpath binary [target/release/genpath of this checkout]
#   --sbatch FLAG     an extra sbatch flag for both jobs (repeatable: --partition=…, --account=…)
#
# Methods that learn (pg, ga, ga-pt) cannot be sharded yet: genpath refuses --shard for them.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
shards=4 cpus=1 mem=2G time=01:00:00 checkpoint=60 tasks="" extra=()
genpath=$(cd "$here/../.." && pwd)/target/release/genpath
usage() { sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d; s/^# \{0,1\}//' >&2; exit 2; }
while (($#)); do
    case $1 in
    --shards) shards=$2; shift 2 ;;
    --cpus) cpus=$2; shift 2 ;;
    --mem) mem=$2; shift 2 ;;
    --time) time=$2; shift 2 ;;
    --checkpoint) checkpoint=$2; shift 2 ;;
    --tasks) tasks=$2; shift 2 ;;
    --genpath) genpath=$2; shift 2 ;;
    --sbatch) extra+=("$2"); shift 2 ;;
    -h | --help) usage ;;
    --) break ;;
    -*) echo "submit.sh: unknown option $1" >&2; usage ;;
    *) break ;;
    esac
done
(($# >= 2)) || usage
scene=$1 out=$2
shift 2
[[ ${1:-} == -- ]] && shift
[[ $shards =~ ^[1-9][0-9]*$ ]] || { echo "submit.sh: --shards must be a positive integer" >&2; exit 2; }
[[ -x $genpath ]] || { echo "submit.sh: $genpath is not an executable genpath (cargo build --release, or --genpath PATH)" >&2; exit 2; }
[[ -f $scene ]] || { echo "submit.sh: $scene: no such scene file" >&2; exit 2; }
command -v sbatch >/dev/null || { echo "submit.sh: sbatch not found: is this a Slurm login node?" >&2; exit 2; }
mkdir -p "$out"
scene=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")
out=$(cd "$out" && pwd)
tasks=${tasks:-0-$((shards - 1))}

export GENPATH="$genpath" GENPATH_SCENE="$scene" GENPATH_OUT="$out" GENPATH_SHARDS="$shards" \
    GENPATH_CHECKPOINT="$checkpoint"
# SIGTERM to the batch shell 60 s before the time limit: the render stops, saves and requeues.
array=$(sbatch --parsable "${extra[@]}" --job-name=genpath-shard --array="$tasks" \
    --requeue --signal=B:TERM@60 --cpus-per-task="$cpus" --mem="$mem" --time="$time" \
    --output="$out/slurm-%A_%a.out" --export=ALL "$here/shard.sbatch" "$@")
array=${array%%;*}
merge=$(sbatch --parsable "${extra[@]}" --job-name=genpath-merge --dependency="afterok:$array" \
    --kill-on-invalid-dep=yes --cpus-per-task=1 --mem="$mem" --time=00:30:00 \
    --output="$out/slurm-%j-merge.out" --export=ALL "$here/merge.sbatch")
merge=${merge%%;*}
echo "shards: job $array (array $tasks of $shards), merge: job $merge → $out/merged.exr"
