#!/usr/bin/env bash
# The whole test suite, from a fresh Debian 12 machine: installs what it needs, builds the
# release configuration (warnings as errors in CI) and runs every test with ctest.
#   bash deploy/run-tests.sh            # everything
#   bash deploy/run-tests.sh -L unit    # extra arguments go to ctest
set -euo pipefail
cd "$(dirname "$0")/.."

bash deploy/install-deps.sh

preset=release
[ "${CI:-}" = "true" ] && preset=ci
cmake --preset "$preset" >/dev/null
cmake --build --preset "$preset" -j "$(nproc)"

# The integration tests use LCM over UDP multicast; they make their own network namespace.
ctest --preset "$preset" --output-on-failure -j "$(nproc)" "$@"
