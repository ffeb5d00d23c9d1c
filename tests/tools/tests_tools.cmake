# The command-line tools (tools/): their shared code, far-client's own logic, and the built
# programs run as a user runs them.

# What the tools share: durations, files to write, command-line errors.
far_add_test(far_cli_test unit tools/cli/cli_common_test.cc)
target_link_libraries(far_cli_test PRIVATE far_cli)

# far-client's logic that needs no daemon: how replay compares a replayed reply with the
# recorded one.
far_add_test(far_client_cli_test unit
  tools/far-client/replay_compare_test.cc
  ${PROJECT_SOURCE_DIR}/tools/far-client/replay_compare.cc)
target_include_directories(far_client_cli_test PRIVATE ${PROJECT_SOURCE_DIR}/tools/far-client)
target_link_libraries(far_client_cli_test PRIVATE far::model)

# far-client links no GL, EGL or FCL (ldd of the binary; far-snapshot, which does, shows that
# the check can fail).
add_test(NAME FarClientLinksTest.LddShowsNoGlEglOrFcl
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/tools/far-client/no_gl_links_test.sh
                 $<TARGET_FILE:far-client> $<TARGET_FILE:far-snapshot>)
set_tests_properties(FarClientLinksTest.LddShowsNoGlEglOrFcl PROPERTIES LABELS unit)

# Unknown commands, the moved snapshot, durations without a unit: one line, exit status 2 (1
# for a bad duration). No daemon: the socket path given does not exist.
add_test(NAME FarClientUsageTest.SaysWhatIsWrongWithTheCommandLineInOneLine
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/tools/far-client/usage_errors_test.sh
                 $<TARGET_FILE:far-client>)
set_tests_properties(FarClientUsageTest.SaysWhatIsWrongWithTheCommandLineInOneLine
                     PROPERTIES LABELS unit)

# Every command of far-client, and far-snapshot, against missing and unwritable paths: one line
# naming the path, a non-zero exit status, never a signal. Nothing reaches GL or a daemon.
add_test(NAME ToolPathErrorsTest.EveryCommandNamesABadPathInOneLineWithoutAborting
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/tools/path_errors_test.sh
                 $<TARGET_FILE:far-client> $<TARGET_FILE:far-snapshot>)
set_tests_properties(ToolPathErrorsTest.EveryCommandNamesABadPathInOneLineWithoutAborting
                     PROPERTIES LABELS unit TIMEOUT 120)

# far-snapshot draws a step (headless GL, llvmpipe in CI). Label gpu.
far_add_test(far_snapshot_test gpu tools/far-snapshot/far_snapshot_test.cc)
target_link_libraries(far_snapshot_test PRIVATE far::io far::scenes)
target_compile_definitions(far_snapshot_test PRIVATE
                           FAR_SNAPSHOT_PATH="$<TARGET_FILE:far-snapshot>")
add_dependencies(far_snapshot_test far-snapshot)
