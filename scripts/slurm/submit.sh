#!/usr/bin/env bash
# Submits one genpath render (or, with --reference, one reference) to Slurm as a job array
# of shards and a merge job:
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
# files. Prints the job ids.
#
# Methods that learn (--method pg, ga or ga-pt among the flags, or no --method: render's
# default is ga-pt) learn once: a learn job
# (scripts/slurm/learn.sbatch) runs `genpath learn SCENE RENDER_FLAGS -o OUTDIR/plan.bin`
# first, the array waits for it (--dependency=afterok) and every task renders with
# `--plan OUTDIR/plan.bin`, and the merge adds the learn job's training shard
# (OUTDIR/plan.bin.shard, pg and ga-pt) to the tasks' shards: learn → array → merge.
# Learning keeps what it finished (the GA's waves, the spatial guide's passes) in
# OUTDIR/plan.bin.learning, so a learn job that Slurm stops is requeued and goes on; with
# --learn-shards L the GA (ga, ga-pt) is split over L jobs: four
# job arrays of L tasks one after another (`learn --shard K/L`, one per wave of the GA),
# then the learn job builds the plan from their waves. With --tasks, an existing
# OUTDIR/plan.bin is used as it is (no learn job).
#
# Options:
#   --shards N        shards (array tasks) [4]
#   --cpus C          CPUs per task, genpath's --threads [1]
#   --mem M           memory per task, as sbatch takes it [2G]
#   --time T          time limit per task run [01:00:00]
#   --checkpoint S    seconds between checkpoints [60]
#   --learn-time T    time limit of each learn job (methods that learn) [the --time]
#   --learn-shards L  split the GA (ga, ga-pt) over L jobs per wave [1: one learn job]
#   --tasks LIST      only these array indices (e.g. 1,5-7): resubmits failed tasks, whose
#                     partial shard files they resume from, with a new merge job
#   --genpath PATH    the genpath binary [target/release/genpath of this checkout]
#   --sbatch FLAG     an extra sbatch flag for both jobs (repeatable: --partition=…, --account=…)
#   --reference       shard `genpath reference` instead of `render` (its two halves in every
#                     shard; its default --method is pt); a method that learns learns both
#                     halves once (`learn --for-reference`), and OUTDIR/merged.exr is the
#                     reference with its noise estimate in merged.exr.json
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
shards=4 cpus=1 mem=2G time=01:00:00 checkpoint=60 tasks="" learn_time="" learn_shards=1 extra=()
command=render
genpath=$(cd "$here/../.." && pwd)/target/release/genpath
usage() { sed -n '2,/^set -euo/p' "${BASH_SOURCE[0]}" | sed '$d; s/^# \{0,1\}//' >&2; exit 2; }
while (($#)); do
    case $1 in
    --shards) shards=$2; shift 2 ;;
    --cpus) cpus=$2; shift 2 ;;
    --mem) mem=$2; shift 2 ;;
    --time) time=$2; shift 2 ;;
    --checkpoint) checkpoint=$2; shift 2 ;;
    --learn-time) learn_time=$2; shift 2 ;;
    --learn-shards) learn_shards=$2; shift 2 ;;
    --tasks) tasks=$2; shift 2 ;;
    --genpath) genpath=$2; shift 2 ;;
    --sbatch) extra+=("$2"); shift 2 ;;
    --reference) command=reference; shift ;;
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
[[ $learn_shards =~ ^[1-9][0-9]*$ ]] || { echo "submit.sh: --learn-shards must be a positive integer" >&2; exit 2; }
[[ -x $genpath ]] || { echo "submit.sh: $genpath is not an executable genpath (cargo build --release, or --genpath PATH)" >&2; exit 2; }
[[ -f $scene ]] || { echo "submit.sh: $scene: no such scene file" >&2; exit 2; }
command -v sbatch >/dev/null || { echo "submit.sh: sbatch not found: is this a Slurm login node?" >&2; exit 2; }
mkdir -p "$out"
scene=$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")
out=$(cd "$out" && pwd)
resubmit=${tasks:+yes}
tasks=${tasks:-0-$((shards - 1))}

# Whether the method learns: then learn once, and every task renders with the plan.
# render's default --method (the GA's best method) where the flags name none; reference's pt.
method=ga-pt
[[ $command == reference ]] && method=pt
for ((i = 1; i <= $#; i++)); do
    arg=${!i}
    case $arg in
    --method=*) method=${arg#--method=} ;;
    --method) j=$((i + 1)); method=${!j:-pt} ;;
    esac
done
plan="" after=()
case $method in
pg | ga | ga-pt)
    plan=$out/plan.bin
    if [[ $method == pg ]] && ((learn_shards > 1)); then
        echo "submit.sh: --learn-shards: pg learns no GA to split (its training runs in one job)" >&2
        exit 2
    fi
    if [[ -z $resubmit || ! -f $plan ]]; then
        # learn_job [ARRAY]: submits a learn job (with ARRAY, an array of the L shards of a
        # wave) after the job in $after; its id becomes the next job's dependency.
        learn_job() {
            local array=() id
            [[ -n $1 ]] && array=(--array="$1")
            shift
            # SIGTERM 60 s before the time limit: learning keeps what it finished and requeues.
            id=$(GENPATH="$genpath" GENPATH_SCENE="$scene" GENPATH_PLAN="$plan" \
                GENPATH_LEARN_SHARDS="$learn_shards" GENPATH_COMMAND="$command" \
                sbatch --parsable "${extra[@]}" "${after[@]}" "${array[@]}" \
                --job-name=genpath-learn --requeue --signal=B:TERM@60 \
                --cpus-per-task="$cpus" --mem="$mem" --time="${learn_time:-$time}" \
                --output="$out/slurm-%j-learn.out" --export=ALL "$here/learn.sbatch" "$@")
            id=${id%%;*}
            after=(--dependency="afterok:$id" --kill-on-invalid-dep=yes)
        }
        if ((learn_shards > 1)); then
            waves=()
            for wave in 0 1 2 3; do
                learn_job "0-$((learn_shards - 1))" "$@"
                waves+=("${after[0]#--dependency=afterok:}")
            done
            echo "learn: waves: jobs ${waves[*]} (arrays of $learn_shards)"
        fi
        learn_job "" "$@"
        echo "learn: job ${after[0]#--dependency=afterok:} → $plan"
    fi
    ;;
esac

export GENPATH="$genpath" GENPATH_SCENE="$scene" GENPATH_OUT="$out" GENPATH_SHARDS="$shards" \
    GENPATH_CHECKPOINT="$checkpoint" GENPATH_PLAN="$plan" GENPATH_COMMAND="$command"
# SIGTERM to the batch shell 60 s before the time limit: the render stops, saves and requeues.
array=$(sbatch --parsable "${extra[@]}" "${after[@]}" --job-name=genpath-shard --array="$tasks" \
    --requeue --signal=B:TERM@60 --cpus-per-task="$cpus" --mem="$mem" --time="$time" \
    --output="$out/slurm-%A_%a.out" --export=ALL "$here/shard.sbatch" "$@")
array=${array%%;*}
merge=$(sbatch --parsable "${extra[@]}" --job-name=genpath-merge --dependency="afterok:$array" \
    --kill-on-invalid-dep=yes --cpus-per-task=1 --mem="$mem" --time=00:30:00 \
    --output="$out/slurm-%j-merge.out" --export=ALL "$here/merge.sbatch")
merge=${merge%%;*}
echo "shards: job $array (array $tasks of $shards), merge: job $merge → $out/merged.exr"
