# Integration tests: real far-daemon processes, the far-client binary and the client library,
# over LCM udpm. Label integration.
#
# Every test process (and gtest_discover_tests' --gtest_list_tests run) goes through
# deploy/netns-run.sh: a private network namespace whose loopback carries multicast, so the
# daemons and clients of one test never hear another test's traffic and nothing leaves the
# host. The property must be set before gtest_discover_tests, which reads it at the call.
if(NOT TARGET far_test_scenes)
  message(STATUS "tests/integration: skipped (needs far_test_scenes from tests/far/tests_gl.cmake)")
  return()
endif()

# The support files, and the test files. CI's sanitizer trees run only the hostile-client and
# thread subsets of deploy/run-sanitizers.sh (BadInputTest, LimitsTest, LcmForgedDatagramTest,
# LcmRouteErrorTest, SessionLifetimeTest, DispatchTest, ManyThreadsTest): with FAR_INTEGRATION_SANITIZER_SUBSET
# (their presets) they build only those files, which cuts a few minutes of CI's 2 cores.
option(FAR_INTEGRATION_SANITIZER_SUBSET "build only the integration tests CI runs under sanitizers" OFF)
find_package(spdlog REQUIRED)  # the in-process daemon tests read its log
set(far_integration_support
  integration/integration_main.cc
  integration/daemon_process.cc
  integration/raw_session.cc
  integration/integration_scenes.cc
  integration/healthy_session.cc
  integration/other_user_client.cc
)
set(far_integration_sanitizer_subset
  integration/bad_input_test.cc
  integration/lcm_receive_test.cc
  integration/lcm_route_error_test.cc
  integration/session_lifetime_test.cc
  integration/dispatch_test.cc
  integration/many_threads_test.cc
)
set(far_integration_tests
  integration/end_to_end_test.cc
  integration/gpu_cost_start_test.cc
  integration/gpu_batch_fallback_test.cc
  integration/readable_output_test.cc
  integration/two_daemons_test.cc
  integration/auto_daemon_test.cc
  integration/privacy_test.cc
  integration/waiting_test.cc
  integration/record_replay_test.cc
  integration/user_limits_test.cc
  integration/fair_shares_test.cc
  integration/memory_test.cc
  integration/cpu_priority_test.cc
  integration/log_flood_test.cc
  integration/out_of_descriptors_test.cc
  integration/socket_directory_test.cc
  integration/lost_datagram_test.cc
  integration/deadline_test.cc
)
if(FAR_INTEGRATION_SANITIZER_SUBSET)
  set(far_integration_tests "")
endif()
add_executable(far_integration_test ${far_integration_support} ${far_integration_sanitizer_subset}
               ${far_integration_tests})
target_link_libraries(far_integration_test PRIVATE far::client far_client_internal far::protocol far::scenes far::io
                      far_server_core
                      far_test_scenes nlohmann_json::nlohmann_json GTest::gtest far_warnings
                      spdlog::spdlog Threads::Threads)
target_compile_definitions(far_integration_test PRIVATE
  FAR_DAEMON_PATH="$<TARGET_FILE:far-daemon>"
  FAR_CLIENT_PATH="$<TARGET_FILE:far-client>"
  FAR_NETNS_RUN_PATH="${PROJECT_SOURCE_DIR}/deploy/netns-run.sh"
  FAR_TEST_GPU_COST_CACHE="${PROJECT_BINARY_DIR}/tests/gpu-costs.json")
add_dependencies(far_integration_test far-daemon far-client)
set_target_properties(far_integration_test PROPERTIES
  CROSSCOMPILING_EMULATOR "${PROJECT_SOURCE_DIR}/deploy/netns-run.sh")
# Discovery (POST_BUILD, like every other suite) runs `netns-run.sh far_integration_test
# --gtest_list_tests` too: on a machine where unshare is not permitted, linking this target
# fails with unshare's message instead of the tests silently not running.
#
# Tests that run alone (RUN_SERIAL). The 32-client fairness test keeps both of CI's cores busy
# for 40 s (70 processes) on purpose, so that it neither starves the daemons of tests beside it
# (a daemon there once took 37 s to start) nor measures their load as unfairness. The light GL
# session's wait beside a heavy one is a bound on 2 cores (issue 41's 1 s; 130-212 ms alone
# since batches are bounded by their fill, 1,019 ms once in CI before). The 16 light sessions that saturate the
# machine must not be demoted, which is judged on their workers' CPU time per step (50 ms):
# with another test beside it, one leaves step's worker once spent 54 ms of CPU (2026-11-29;
# alone, 3 of 3 runs passed), so it too runs alone.
set(far_integration_serial_tests
    "AutoDaemonTest.ThirtyTwoClientsFindTheirGpusDaemonAndAreServedFairly:DeadlineTest.LightSessionsBesideAHeavy*:CpuPriorityTest.LightSessionsThatSaturateTheMachineTogetherAreNotDemoted")
gtest_discover_tests(far_integration_test
  TEST_FILTER "-${far_integration_serial_tests}"
  PROPERTIES LABELS integration TIMEOUT 120
  DISCOVERY_TIMEOUT 60)
if(NOT FAR_INTEGRATION_SANITIZER_SUBSET)
  gtest_discover_tests(far_integration_test
    TEST_FILTER "${far_integration_serial_tests}"
    PROPERTIES LABELS integration TIMEOUT 120 RUN_SERIAL TRUE
    DISCOVERY_TIMEOUT 60)
endif()

# far-daemon's Prometheus metrics (tests/integration/metrics_test.py): the file and the port
# parse with prometheus_client's parser and match far-client status, the file is never read
# partial, and the port listens on 127.0.0.1 only. Each in a network namespace of its own.
foreach(mode values loopback)
  set(name MetricsTest.FileAndPortMatchTheStatusAndTheFileIsNeverReadPartial)
  if(mode STREQUAL "loopback")
    set(name MetricsTest.ThePortListensOnLoopbackOnlyAndATakenPortIsAStartError)
  endif()
  add_test(NAME ${name}
           COMMAND ${PROJECT_SOURCE_DIR}/deploy/netns-run.sh /usr/bin/python3
                   ${CMAKE_CURRENT_SOURCE_DIR}/integration/metrics_test.py ${mode}
                   $<TARGET_FILE:far-daemon> $<TARGET_FILE:far-client>)
  set_tests_properties(${name} PROPERTIES LABELS integration TIMEOUT 120
    ENVIRONMENT "FAR_TEST_GPU_COST_CACHE=${PROJECT_BINARY_DIR}/tests/gpu-costs.json")
endforeach()
