#!/bin/sh
# shellcheck disable=SC2016 # the backquotes in the patterns are Markdown, not commands
# ctest FarStudy.SmokeRunWritesCsvTablesAndBars (label gpu: it needs an EGL context, llvmpipe will
# do). far-study on a small breaking (4 steps, the vase breaks at step 2) and scaling-2000, the
# default configurations, the distance pass on both, the reference on one step (--reference-steps 1: step 1,
# and on breaking also the break and the step after it), --results on a scratch copy of a RESULTS
# file; then checks the exit status, the CSV rows, the tables, the bars and that --results kept
# everything outside the study section. Also: --methods runs only what it names, bad flags exit 2.
#   study_smoke_test.sh path/to/far-study path/to/RESULTS.md
set -eu
study="$1"
results_in="$2"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
: > "$out/log"

fail() {
  echo "FAIL: $*"
  echo "--- far-study output:"
  cat "$out/log"
  exit 1
}

# Bad flags (and an output folder that cannot be made): exit status 2, before any GL work.
for flags in "--methods far,bogus" "--scenes nope" "--reference-steps -1" \
  "--distance-fraction 2" "--paper-gpu far/id-buffer/x" "--no-such-flag" \
  "--csv /proc/no/such/study.csv"; do
  rc=0
  # shellcheck disable=SC2086 # a list of flags
  "$study" $flags > "$out/log" 2>&1 || rc=$?
  [ "$rc" -eq 2 ] || fail "far-study $flags: exit status $rc, not 2"
done

# A scratch copy of the RESULTS file: only its study section may change.
cp "$results_in" "$out/RESULTS.md"
outside() { sed '/<!-- study:begin -->/,/<!-- study:end -->/d' "$1"; }
outside "$results_in" > "$out/outside.before"

"$study" --scenes breaking,scaling-2000 --steps 4 --breaking-static-triangles 3000 \
  --breaking-rigid-triangles 1000 --distance all --reference-steps 1 --csv "$out/study.csv" \
  --results "$out/RESULTS.md" \
  > "$out/log" 2>&1 || fail "far-study exited with $?"

csv="$out/study.csv"
md="$out/RESULTS.md"
grep -q 'the vase breaks at measured step 2 of 4' "$out/log" || fail "breaking did not break at 2"
head -n 1 "$csv" | grep -q ',checked,checked_steps,method_run,' || fail "CSV header: $(head -n 1 "$csv")"
# field of the CSV row of scene $1, config $2, output $3, by header name $4
field() {
  awk -F, -v s="$1" -v c="$2" -v o="$3" -v f="$4" '
    NR == 1 { for (i = 1; i <= NF; i++) col[$i] = i; next }
    $1 == s && $7 == c && $11 == o { print $col[f]; found = 1 }
    END { if (!found) print "missing" }' "$csv"
}
expect() {
  got=$(field "$1" "$2" "$3" "$4")
  [ "$got" = "$5" ] || fail "$1 $2 $3: $4 is '$got', expected '$5'"
}
for scene in breaking scaling-2000; do
  for config in aabb bvh auto fcl far/id-buffer/256; do
    expect "$scene" "$config" contacts checked 1
  done
  expect "$scene" far/id-buffer/256 contacts missed_total 0
  for config in aabb bvh far/id-buffer/256; do
    expect "$scene" "$config" distance missed_total 0
  done
  expect "$scene" bvh contacts missed_total 0
  expect "$scene" bvh contacts false_positives_total 0
  expect "$scene" bvh distance distance_missed_total 0
  expect "$scene" bvh distance distance_spurious_total 0
  expect "$scene" bvh contacts samples 4
  [ "$(field "$scene" fcl distance samples)" = missing ] || fail "fcl ran a distance pass"
done
# breaking: the reference on step 1, the break (2) and the step after it (3); scaling: step 1.
expect breaking bvh contacts checked_steps 3
expect breaking exact distance samples 3
expect breaking far/occlusion-query/256 contacts checked_steps 3
expect breaking far-exact-offset/id-buffer/256 contacts checked_steps 3
expect breaking cullide/id-buffer/256 contacts samples 4
expect scaling-2000 bvh contacts checked_steps 1
expect scaling-2000 exact distance samples 1
[ "$(field breaking exact distance reference_total)" -gt 0 ] || fail "breaking: no reference contacts"
[ "$(field breaking exact distance distance_reference_total)" -gt 0 ] ||
  fail "breaking: no reference distance pairs"

grep -q '^Reference: the brute force (`exact`) on measured steps 1, 2, 3 of 4 ' "$md" ||
  fail "breaking's table does not say which steps the reference checked"
grep -q '^Reference: the brute force (`exact`) on measured steps 1 of 4 ' "$md" ||
  fail "scaling-2000's table does not say which steps the reference checked"
grep -q '^| bvh | - | - | contacts | .* | 0 | 0 | 3 of 4 | - |' "$md" ||
  fail "breaking's bvh row does not say 3 of 4 steps checked"
grep -q '^#### breaking: BreakingScene' "$md" || fail "no breaking table"
grep -q '^#### scaling-2000: ScalingScene' "$md" || fail "no scaling-2000 table"
grep -q '^### Scaling family' "$md" || fail "no scaling table"
for bar in "auto within 1.2x" "CPU path: bvh" "GL path: FAR"; do
  grep "^| $bar" "$md" | grep -Eq '\| (met|\*\*not met\*\*|met where checked[^|]*|not evaluated) \|$' ||
    fail "bar '$bar' has no verdict"
done
grep -q '^| breaking | breaking | [0-9]* | [^|]* | [^|]* | [^|]* | [^|]* | 0 / 0 (3 of 4 steps checked) |' \
  "$md" || fail "the CPU path table does not give bvh's misses with the steps checked"
grep -q '^| breaking | [0-9]* | [^|]* | [^|]* | 0 / 0 (3 of 4 steps checked) |' "$md" ||
  fail "auto's table does not give breaking's misses with the steps checked"
grep -q 'breaking,scaling-2000' "$md" || fail "the study section does not have this run's command"
outside "$md" > "$out/outside.after"
cmp -s "$out/outside.before" "$out/outside.after" ||
  fail "--results changed the file outside the study section: $(diff "$out/outside.before" "$out/outside.after" | head)"
if command -v gnuplot > /dev/null; then
  for png in study.png study_scaling.png; do
    [ -s "$out/$png" ] || fail "no $png (gnuplot is there)"
  done
fi

# --methods runs only what it names (and the reference); a missing output folder is made.
few="$out/new/folder/few.csv"
"$study" --scenes scaling-1000 --steps 1 --methods bvh --distance none --csv "$few" \
  > "$out/log" 2>&1 || fail "far-study --methods bvh exited with $?"
[ "$(tail -n +2 "$few" | cut -d, -f7 | sort | tr '\n' ' ')" = "bvh exact " ] ||
  fail "--methods bvh ran $(tail -n +2 "$few" | cut -d, -f7 | tr '\n' ' ')"
echo "far-study smoke run: ok"
