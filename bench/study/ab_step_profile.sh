#!/bin/bash
# A/B of far-step-profile binaries on one scene: runs each binary in turn, RUNS times, and
# prints per binary the median and quartiles of the step times of steps 1-4 of all its runs, then
# the median of each step on its own (a scene whose steps differ, such as breaking's, is read there).
# The binaries alternate so that the machine's drift (20-40% on a shared VM) hits them alike.
# Usage: bench/study/ab_step_profile.sh SCENE RUNS THREADS IDLE_MS BINARY...
#   e.g. cp build/release/bench/study/far-step-profile /tmp/old  (then rebuild the change)
#        bench/study/ab_step_profile.sh scaling-5000 8 2 6 /tmp/old build/release/bench/study/far-step-profile
# FAR_STEP_PROFILE_ARGS adds flags to every run (e.g. '--distance-fraction 0.001');
# FAR_STEP_PROFILE_METHOD is the method (default bvh; gpu runs on the GL context).
set -euo pipefail
if [[ $# -lt 5 ]]; then
  sed -n '2,8p' "$0" >&2
  exit 2
fi
scene=$1 runs=$2 threads=$3 idle_ms=$4
shift 4
declare -A times
declare -A step_times # "binary step" -> that step's times
for _ in $(seq "$runs"); do
  for binary in "$@"; do
    # shellcheck disable=SC2086 # FAR_STEP_PROFILE_ARGS is a list of flags
    output=$("$binary" --scene "$scene" --method "${FAR_STEP_PROFILE_METHOD:-bvh}" --threads "$threads" --steps 4 \
      --idle-ms "$idle_ms" ${FAR_STEP_PROFILE_ARGS:-} | awk -F, 'NR > 1 && $1 >= 1 { print $1, $2 }')
    while read -r step ms; do
      times[$binary]="${times[$binary]:-} $ms"
      step_times["$binary $step"]="${step_times["$binary $step"]:-} $ms"
    done <<<"$output"
  done
done
for binary in "$@"; do
  # shellcheck disable=SC2086  # word splitting intended: one time per line
  printf '%s %s t=%s idle=%s ms: %s\n' "$binary" "$scene" "$threads" "$idle_ms" \
    "$(printf '%s\n' ${times[$binary]} | sort -n | awk '{ t[NR] = $1 } END {
      printf "median %.3f p25 %.3f p75 %.3f n %d", t[int(NR / 2) + 1], t[int(NR / 4) + 1],
        t[int(3 * NR / 4) + 1], NR }')"
done
for binary in "$@"; do
  for step in 1 2 3 4; do
    # shellcheck disable=SC2086  # word splitting intended: one time per line
    printf '%s %s step %s ms: %s\n' "$binary" "$scene" "$step" \
      "$(printf '%s\n' ${step_times["$binary $step"]:-} | sort -n | awk '{ t[NR] = $1 } END {
        printf "median %.3f n %d", t[int(NR / 2) + 1], NR }')"
  done
done
