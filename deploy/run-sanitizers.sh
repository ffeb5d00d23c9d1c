#!/usr/bin/env bash
# CI's sanitizer and fuzzing stages (docs/testing.md says what runs and why), each in its own
# clang build tree next to the release one:
#   asan  build/ci-asan: ASan + UBSan. The unit tests of every layer that reads outside input
#         (protocol, server, io, model), the integration tests that play hostile clients, and a
#         smoke run of every libFuzzer target from its committed corpus.
#   tsan  build/ci-tsan: ThreadSanitizer. The protocol, server, pairs and client unit tests
#         (pairs: the CPU pool and the stages that run on it; client: the receiving thread a
#         process's Clients share) and the integration tests of the daemon's
#         threads (sessions opening and closing, dispatch, hostile clients writing shared
#         memory while the daemon reads it or flooding it, one process stepping many sessions
#         from many threads).
#   bash deploy/run-sanitizers.sh            # both
#   bash deploy/run-sanitizers.sh asan       # one
# Assumes deploy/install-deps.sh has run. Prints each stage's wall and CPU time.
set -euo pipefail
cd "$(dirname "$0")/.."

jobs=$(nproc)

stage_timer_name=run-sanitizers
# shellcheck source=deploy/stage-timer.sh
source deploy/stage-timer.sh

# Unit tests (the executables this tree built: the others show as <target>_NOT_BUILT). The
# tools' script tests (label unit) run far-client and far-snapshot on bad paths and command
# lines: built here too, so that those error paths run under the sanitizers.
asan_unit_targets=(far_protocol_test far_server_test far_io_test far_model_test far-client
  far-snapshot)
# Integration tests that send the daemon what a hostile or careless client would, and LCM's
# error path when its multicast group has no route (a use-after-free fixed in far's LCM patch).
asan_integration='^(BadInputTest|LimitsTest|LcmForgedDatagramTest|LcmRouteErrorTest)\.'
tsan_unit_targets=(far_protocol_test far_server_test far_pairs_test far_client_receiver_test
  far-client far-snapshot)
# Of the hostile-input tests, those where a second thread or process touches what the daemon's
# threads read (the rings and the segment scribbled, resized or overrun while they work; floods
# and bursts across sessions): the others check one message's validation on the LCM thread,
# which ASan runs (above) and which SessionLifetimeTest and DispatchTest cross here.
tsan_bad_input='RingScribbledWhileTheDaemonReadsGetsErrorsNotACrash|ReplyRingReadIndexScribbledIsAnErrorAndTheSessionRecovers|TheClientCannotResizeTheSegmentAndHolesAreZerosNotASigbus|WriteIndexOrRecordSizePastTheCapacityIsAFramingError|RecordRunningPastTheWrittenEndCorruptsOnlyThatSession|BurstFromOneSessionDoesNotDropAnotherSessionsRequests|StepFloodIsAnsweredWithBusyWhileOthersAreServed'
tsan_integration="^((SessionLifetimeTest|DispatchTest|ManyThreadsTest)\\..*|BadInputTest\\.($tsan_bad_input))\$"

configure() {
  cmake --preset "$1" >/dev/null
}

asan() {
  timed asan-configure configure ci-asan
  local fuzzers
  fuzzers=$(sed -n 's/^far_add_fuzzer(\([a-z_]*\) .*/far_fuzz_\1/p' tests/fuzz/CMakeLists.txt)
  # shellcheck disable=SC2086
  timed asan-build cmake --build build/ci-asan -j "$jobs" --target "${asan_unit_targets[@]}" \
    far_integration_test $fuzzers
  timed asan-unit ctest --preset ci-asan -j "$jobs" -L unit -E '_NOT_BUILT$|^InstallConsumerTest'
  # Leak checks off for the daemons: Mesa's driver leaks a few hundred bytes per GL context and
  # is unloaded at exit, so LeakSanitizer cannot even name it. Memory errors stay fatal.
  timed asan-integration env ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build/ci-asan --output-on-failure -j "$jobs" -L integration \
    -R "$asan_integration"
  timed asan-fuzz ctest --preset ci-asan -j "$jobs" -L fuzz
}

tsan() {
  timed tsan-configure configure ci-tsan
  timed tsan-build cmake --build build/ci-tsan -j "$jobs" --target "${tsan_unit_targets[@]}" \
    far_integration_test
  timed tsan-unit ctest --preset ci-tsan -j "$jobs" -L unit -E '_NOT_BUILT$|^InstallConsumerTest'
  timed tsan-integration ctest --preset ci-tsan -j "$jobs" -L integration -R "$tsan_integration"
}

case "${1:-all}" in
  asan) asan ;;
  tsan) tsan ;;
  all)
    asan
    tsan
    ;;
  *)
    echo "usage: $0 [asan|tsan|all]" >&2
    exit 2
    ;;
esac
