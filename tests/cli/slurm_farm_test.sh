#!/usr/bin/env bash
# CTest SlurmFarm: an animation on a real Slurm cluster equals one single-process run, byte for byte.
#
# Starts a single-node cluster from Debian's packages in a temporary folder (tests/scripts/
# slurm_cluster.sh: munged with its own key, slurmctld and slurmd with a generated slurm.conf),
# submits 6 tiny frames with scripts/slurm_animate.sh as a job array of 3 tasks (keys job, array,
# encode job; task 1's first attempt fails after one frame, so the scheduler's requeue and the
# resume run too), waits, and compares every frame file, the contact sheet and the MP4s with
# `dynsky animate` run once in this process's machine. Exit 77 (skipped) only when Slurm is not
# installed or does not start; everything it started is stopped by pid on the way out.
#   slurm_farm_test.sh DYNSKY SOURCE_DIR
set -uo pipefail

dynsky=$1
src=$2
# shellcheck source=../scripts/slurm_cluster.sh
source "$src/tests/scripts/slurm_cluster.sh"

tmp=$(mktemp -d /tmp/dynsky-slurm.XXXXXX)  # short: munge's socket path must fit a sockaddr_un
ok=0
cleanup() {
  slurm_cluster_stop
  if ((ok)); then rm -rf "$tmp"; else echo "slurm_farm_test: kept $tmp (logs in cluster/log, farm/logs)"; fi
}
trap cleanup EXIT

if ! slurm_cluster_start "$tmp/cluster"; then
  echo "slurm_farm_test: SKIPPED: Slurm cannot be started here (scripts/setup.sh installs munge slurmctld slurmd" \
    "slurm-client on Debian 12)"
  ok=1
  exit 77
fi

args=(builtin --sky procedural:3 --model procedural --sky-res 64 --res 48x27 --spp 2 --max-depth 3
  --duration 1.5 --fps 4 --dt 0.5 --threads 1)
fail() {
  echo "slurm_farm_test: FAILED: $*"
  for f in "$tmp"/farm/logs/*.log; do [[ -f $f ]] && { echo "--- $f"; tail -20 "$f"; }; done
  exit 1
}

start=$(date +%s)
"$dynsky" animate "${args[@]}" --out "$tmp/one" >"$tmp/one.log" 2>&1 || fail "the single-process run: $(tail -5 "$tmp/one.log")"
echo "slurm_farm_test: single-process run: $(($(date +%s) - start)) s"

start=$(date +%s)
DYNSKY_FARM_FAIL_TASK=1 timeout 150 "$src/scripts/slurm_animate.sh" --out "$tmp/farm" --tasks 3 --dynsky "$dynsky" \
  --wait -- "${args[@]}" || fail "the Slurm run did not complete"
echo "slurm_farm_test: Slurm run (keys, 3 tasks with one requeue, encode): $(($(date +%s) - start)) s"

# Task 1 failed once after its first frame; the scheduler ran it again and it kept that frame.
grep -q "requeueing" "$tmp"/farm/logs/frames-*_1.log || fail "task 1 was not requeued"
grep -q "1 frame(s) rendered, 1 already complete (kept)" "$tmp"/farm/logs/frames-*_1.log ||
  fail "task 1's second attempt did not resume"

count=0
for f in "$tmp"/one/frame_*.exr "$tmp"/one/frame_*.png "$tmp"/one/sky_*.png "$tmp/one/contact_sheet.png" \
  "$tmp/one/animation.mp4" "$tmp/one/sky.mp4"; do
  name=$(basename "$f")
  cmp "$f" "$tmp/farm/$name" || fail "$name differs from the single-process run's"
  count=$((count + 1))
done
((count == 6 * 3 + 3)) || fail "expected 21 files to compare, found $count"
# No task wrote a file another wrote: timings per task, no temporaries left.
for range in 0-1 2-3 4-5; do [[ -f $tmp/farm/timings_$range.csv ]] || fail "timings_$range.csv missing"; done
[[ -z $(find "$tmp/farm" -name '.tmp-*') ]] || fail "temporaries left: $(find "$tmp/farm" -name '.tmp-*')"
echo "slurm_farm_test: $count files identical to the single-process run's"
ok=1
