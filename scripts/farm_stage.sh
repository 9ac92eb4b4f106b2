#!/usr/bin/env bash
# One stage of an animation spread over a render farm (docs/render-farm.md), the same for every
# scheduler: Slurm's array tasks (scripts/slurm_animate.sh) and Kubernetes' Indexed Jobs
# (scripts/k8s/dynsky-animate.yaml) run it with their task index.
#
#   scripts/farm_stage.sh STAGE --out DIR [--task I | --task-env VAR] [--tasks N] [--dynsky PATH] -- ANIMATE_ARGS...
#
# --task-env names the variable holding the index: SLURM_ARRAY_TASK_ID, JOB_COMPLETION_INDEX.
#
#   keys    dynsky animate ARGS --stage keys: the stored timeline DIR/timeline for the whole duration
#   frames  task I of N: frames [I*S, min(I*S+S, F)-1] with S = ceil(F / N), F the frame count
#           (dynsky animate --count-frames); a task past the last frame has nothing to do
#   encode  dynsky animate ARGS --stage encode: MP4s and contact sheet once every frame is complete
#
# Every stage passes the same ANIMATE_ARGS, then --out DIR --timeline DIR/timeline (they win: a
# repeated option takes its last value), so every task agrees on the frame settings. Each stage
# resumes: keys keeps a complete timeline of the same settings, frames keeps complete frames.
set -euo pipefail

usage() { sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; }
case ${1:-} in -h | --help) usage; exit 0 ;; esac
stage=${1:-}
shift || true
out="" task="" tasks="" dynsky=""
while (($#)); do
  case $1 in
    --out) out=$2; shift 2 ;;
    --task) task=$2; shift 2 ;;
    --task-env) task=${!2:-}; shift 2 ;;  # the scheduler's index variable, read here
    --tasks) tasks=$2; shift 2 ;;
    --dynsky) dynsky=$2; shift 2 ;;
    --) shift; break ;;
    -h | --help) usage; exit 0 ;;
    *) echo "farm_stage: unknown option '$1' (before --)" >&2; exit 2 ;;
  esac
done
[[ -n $out ]] || { echo "farm_stage: --out DIR is required" >&2; exit 2; }
if [[ -z $dynsky ]]; then
  dynsky=$(command -v dynsky || echo "$(cd "$(dirname "$0")/.." && pwd)/build/cli/dynsky")
fi
args=("$@" --out "$out" --timeline "$out/timeline")

case $stage in
  keys) exec "$dynsky" animate "${args[@]}" --stage keys ;;
  encode) exec "$dynsky" animate "${args[@]}" --stage encode ;;
  frames)
    [[ $task =~ ^[0-9]+$ && $tasks =~ ^[1-9][0-9]*$ ]] || {
      echo "farm_stage: frames needs --task I --tasks N (got '$task' of '$tasks')" >&2
      exit 2
    }
    total=$("$dynsky" animate "${args[@]}" --count-frames)
    size=$(((total + tasks - 1) / tasks))
    first=$((task * size))
    last=$((first + size - 1 < total - 1 ? first + size - 1 : total - 1))
    if ((first > total - 1)); then
      echo "farm_stage: task $task of $tasks: no frames (the animation has $total)"
      exit 0
    fi
    # Test hook (tests/cli/slurm_farm_test.sh): the first attempt of this task renders one frame and
    # fails, as a crashed node would, so the scheduler's retry and the resume are exercised.
    if [[ -n ${DYNSKY_FARM_FAIL_TASK:-} && $DYNSKY_FARM_FAIL_TASK == "$task" && ${SLURM_RESTART_COUNT:-0} == 0 ]]; then
      "$dynsky" animate "${args[@]}" --stage frames --frames "$first-$first"
      echo "farm_stage: task $task failing on purpose (DYNSKY_FARM_FAIL_TASK)" >&2
      exit 1
    fi
    echo "farm_stage: task $task of $tasks: frames $first-$last of $total"
    exec "$dynsky" animate "${args[@]}" --stage frames --frames "$first-$last"
    ;;
  *) echo "farm_stage: stage must be keys, frames or encode (got '$stage')" >&2; exit 2 ;;
esac
