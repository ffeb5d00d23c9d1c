#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: installs what it needs, builds the
# release configuration (warnings as errors in CI) and runs every test with ctest. In CI (and
# with FAR_SANITIZERS=1) the sanitizer and fuzzing stages (deploy/run-sanitizers.sh) run before
# the final ctest, whose summary stays the last output. docs/testing.md says what runs.
#   bash deploy/run-tests.sh            # everything
#   bash deploy/run-tests.sh -L unit    # extra arguments go to ctest
set -euo pipefail
cd "$(dirname "$0")/.."

# Sets `cpu` to the CPU seconds this shell's finished children used (bash's `times`, second
# line). `times` must run in this shell, not in a $(...) subshell, whose children are its own.
cpu_file=$(mktemp)
trap 'rm -f "$cpu_file"' EXIT
children_cpu() {
  times >"$cpu_file"
  cpu=$(awk 'NR == 2 {
    for (i = 1; i <= 2; ++i) { split($i, t, /[ms]/); total += 60 * t[1] + t[2] }
    printf "%d", total }' "$cpu_file")
}

# Runs a stage and says how long it took: wall time, and CPU time (meaningful when the machine
# is shared: CPU seconds / cores is what the stage would take alone).
timed() {
  local name=$1
  shift
  local start=$SECONDS before
  children_cpu
  before=$cpu
  "$@"
  children_cpu
  echo "run-tests: stage $name took $((SECONDS - start)) s ($((cpu - before)) s CPU)" >&2
}

timed install-deps bash deploy/install-deps.sh

preset=release
sanitizers=${FAR_SANITIZERS:-0}
if [ "${CI:-}" = "true" ]; then
  preset=ci
  sanitizers=${FAR_SANITIZERS:-1}
fi
timed configure cmake --preset "$preset" >/dev/null
timed build cmake --build --preset "$preset" -j "$(nproc)"

if [ "$sanitizers" = 1 ]; then timed sanitizers bash deploy/run-sanitizers.sh; fi

# The integration tests use LCM over UDP multicast; they make their own network namespace.
ctest --preset "$preset" --output-on-failure -j "$(nproc)" "$@"
