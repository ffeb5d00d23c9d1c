#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: installs what it needs, builds the
# release configuration (warnings as errors in CI) and runs every test with ctest. In CI (and
# with FAR_SANITIZERS=1) the sanitizer and fuzzing stages (deploy/run-sanitizers.sh) run before
# the final ctest, whose summary stays the last output. docs/testing.md says what runs.
#   bash deploy/run-tests.sh            # everything
#   bash deploy/run-tests.sh -L unit    # extra arguments go to ctest
set -euo pipefail
cd "$(dirname "$0")/.."

stage_timer_name=run-tests
# shellcheck source=deploy/stage-timer.sh
source deploy/stage-timer.sh

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
