# far_add_test(<name> <label> <sources...>) for far-client's own logic that needs no daemon:
# how replay compares a replayed reply with the recorded one.
far_add_test(far_client_cli_test unit
  client/replay_compare_test.cc
  ${PROJECT_SOURCE_DIR}/client/src/cli/replay_compare.cc)
target_include_directories(far_client_cli_test PRIVATE ${PROJECT_SOURCE_DIR}/client/src/cli)
target_link_libraries(far_client_cli_test PRIVATE far::model)
