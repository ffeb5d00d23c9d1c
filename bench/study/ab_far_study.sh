#!/usr/bin/env bash
# A/B of two far-study binaries on the run of record's command (bench/RESULTS.md, "Accuracy and
# cost study"): runs them A, B, B, A so that the machine's drift hits both alike, each writing
# OUT/<run>.csv, then compares (ab_far_study_compare.py): every answer count must be equal, and
# the step times are reported as B/A ratios of the two runs' mean, with the A-A and B-B spread.
# Run from the source tree (bench/data/bunny.obj). About 4 x 4-6 min on 2 cores.
# Usage: bench/study/ab_far_study.sh OUT A_FAR_STUDY B_FAR_STUDY
#   e.g. git worktree add /tmp/base <commit> (build it), then
#        bench/study/ab_far_study.sh /tmp/ab /tmp/base/build/release/bench/study/far-study \
#          build/release/bench/study/far-study
set -euo pipefail
if [[ $# -ne 3 ]]; then
  sed -n '2,10p' "$0" >&2
  exit 2
fi
out=$1 a=$2 b=$3
mkdir -p "$out"
args=(--scenes soup,bunnies,leaves,bunnies-fine,paper-leaves,breaking,paper-bunnies,scaling
  --scaling-sizes 5000,10000,20000,50000,100000,200000,300000 --steps 4 --repeat 1
  --resolutions 256,512,1024,2048
  --paper-gpu far/id-buffer/256,far/occlusion-query/256,far-exact-offset/id-buffer/256,far-exact-offset/occlusion-query/256,cullide/id-buffer/256
  --scaling-gpu far/id-buffer/256 --scaling-gpu-max 50000 --scaling-reference-max 300000
  --reference-steps 2 --distance paper --distance-fraction 0.001 --oq-steps 0
  --bunny bench/data/bunny.obj --bunny-subdivisions 0 --fine-subdivisions 1 --fine-steps 2
  --paper-bunny-refinement 5 --breaking-static-triangles 100000 --breaking-rigid-triangles 35000
  --soup-objects 32 --soup-triangles 48 --leaves 60 --leaf-cells 6 --gl-platform auto)
for run in A1 B1 B2 A2; do
  binary=$a
  [[ $run == B* ]] && binary=$b
  start=$(date +%s)
  "$binary" "${args[@]}" --csv "$out/$run.csv" >"$out/$run.out" 2>&1
  echo "$run: $(($(date +%s) - start)) s"
done
/usr/bin/python3 "$(dirname "$0")/ab_far_study_compare.py" "$out"
