#!/usr/bin/env bash
# An animation on a Slurm cluster (docs/render-farm.md): submits three jobs and returns.
#
#   scripts/slurm_animate.sh --out DIR [--tasks N] [--retries R] [--dynsky PATH] [--sbatch "ARGS"] [--wait] \
#       -- SCENE [dynsky animate options...]
#
#   1. keys    dynsky animate --stage keys: the medium steps and flows of the whole duration, once,
#              into DIR/timeline
#   2. frames  a job array of N tasks (SLURM_ARRAY_TASK_ID), after keys: task I renders frames
#              [I*S, I*S+S-1], S = ceil(F / N) from the frame count F (scripts/farm_stage.sh)
#   3. encode  after every task: animation.mp4, sky.mp4 and contact_sheet.png
#
# DIR must be on a filesystem every node sees at the same path (as must the scene, the sky files and
# dynsky itself). --tasks defaults to one task per 8 frames (at most 1000, Slurm's default
# MaxArraySize is 1001). Every job is submitted with --requeue (the scheduler reruns it after a node
# failure or preemption) and, when a run fails, requeues itself up to --retries times (default 2);
# dynsky resumes, keeping the frames already complete. --sbatch adds options to every sbatch call
# (partition, account, time limit, CPUs: "--partition=render --cpus-per-task=32 --time=2:00:00").
# --wait blocks until the encode job is over; the exit status says whether it completed.
# Logs: DIR/logs/. Prints the three job ids.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)

# Inside a job (sbatch runs a copy of this script): one stage, requeued on failure.
if [[ ${1:-} == --run ]]; then
  stage=$2 farm_stage=$3 retries=$4
  shift 4
  rc=0
  "$farm_stage" "$stage" "$@" || rc=$?
  if ((rc != 0)); then
    attempt=${SLURM_RESTART_COUNT:-0}
    if ((attempt < retries)); then
      echo "slurm_animate: $stage failed (exit $rc) on attempt $((attempt + 1)); requeueing job $SLURM_JOB_ID" >&2
      # The scheduler stops this run and starts the job again later, possibly on another node.
      scontrol requeue "$SLURM_JOB_ID" && sleep 600
    fi
    echo "slurm_animate: $stage failed (exit $rc) after $((attempt + 1)) attempt(s)" >&2
  fi
  exit "$rc"
fi

out="" tasks="" retries=2 dynsky="" sbatch_extra="" wait=0
while (($#)); do
  case $1 in
    --out) out=$2; shift 2 ;;
    --tasks) tasks=$2; shift 2 ;;
    --retries) retries=$2; shift 2 ;;
    --dynsky) dynsky=$2; shift 2 ;;
    --sbatch) sbatch_extra=$2; shift 2 ;;
    --wait) wait=1; shift ;;
    --) shift; break ;;
    -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
    *) echo "slurm_animate: unknown option '$1' (animate options go after --)" >&2; exit 2 ;;
  esac
done
[[ -n $out ]] || { echo "slurm_animate: --out DIR is required" >&2; exit 2; }
(($# > 0)) || { echo "slurm_animate: give the animation after --: SCENE [dynsky animate options]" >&2; exit 2; }
[[ $retries =~ ^[0-9]+$ ]] || { echo "slurm_animate: --retries must be a whole number" >&2; exit 2; }
if [[ -z $dynsky ]]; then dynsky=$(command -v dynsky || echo "$here/../build/cli/dynsky"); fi
dynsky=$(realpath "$dynsky")
mkdir -p "$out/logs"
out=$(realpath "$out")

# The frame count decides the shards; dynsky checks the options and that the scene, sky and model
# exist on the way (a typo fails here, before anything is queued).
total=$("$dynsky" animate "$@" --out "$out" --count-frames)
if [[ -z $tasks ]]; then
  tasks=$(((total + 7) / 8))
  ((tasks <= 1000)) || tasks=1000
fi
[[ $tasks =~ ^[1-9][0-9]*$ ]] || { echo "slurm_animate: --tasks must be a positive whole number" >&2; exit 2; }
size=$(((total + tasks - 1) / tasks))
tasks=$(((total + size - 1) / size))  # no task without frames

# shellcheck disable=SC2206  # --sbatch is a list of options, split on spaces on purpose
extra=($sbatch_extra)
common=(--parsable --requeue --open-mode=append --chdir="$PWD" "${extra[@]}")
stage_args=(--out "$out" --dynsky "$dynsky")
keys=$(sbatch "${common[@]}" --job-name=dynsky-keys --output="$out/logs/keys-%j.log" \
  "$0" --run keys "$here/farm_stage.sh" "$retries" "${stage_args[@]}" -- "$@")
frames=$(sbatch "${common[@]}" --job-name=dynsky-frames --array="0-$((tasks - 1))" \
  --dependency="afterok:$keys" --kill-on-invalid-dep=yes --output="$out/logs/frames-%A_%a.log" \
  "$0" --run frames "$here/farm_stage.sh" "$retries" "${stage_args[@]}" --task-env SLURM_ARRAY_TASK_ID --tasks "$tasks" -- "$@")
encode=$(sbatch "${common[@]}" --job-name=dynsky-encode --dependency="afterok:$frames" --kill-on-invalid-dep=yes \
  --output="$out/logs/encode-%j.log" "$0" --run encode "$here/farm_stage.sh" "$retries" "${stage_args[@]}" -- "$@")
echo "slurm_animate: $total frames in $tasks task(s) of $size; jobs: keys $keys, frames $frames, encode $encode"

((wait)) || exit 0
while [[ -n $(squeue -h -j "$keys,$frames,$encode" 2>/dev/null) ]]; do sleep 1; done
state=$(scontrol show job -o "$encode" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2 || true)
echo "slurm_animate: encode job $encode: ${state:-gone from the queue}"
[[ $state == COMPLETED ]]
