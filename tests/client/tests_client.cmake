# far::client's logic that needs no daemon: how it finds one (discovery.h).
far_add_test(far_client_test unit client/discovery_test.cc)
target_link_libraries(far_client_test PRIVATE far::client)

# The receiving thread a process's Clients share (client/src/shared_receiver.h) and the LCM
# subscriptions it makes and ends while it handles, over udpm in a private network namespace
# (deploy/netns-run.sh, as the integration tests): LCM's in-process memq:// guards its queue
# with a glib mutex ThreadSanitizer cannot see, so CI's tsan tree would report its handoffs.
add_executable(far_client_receiver_test client/shared_receiver_test.cc)
target_link_libraries(far_client_receiver_test PRIVATE far::client far::protocol far_warnings
                      GTest::gtest GTest::gtest_main)
target_include_directories(far_client_receiver_test PRIVATE ${PROJECT_SOURCE_DIR}/client/src)
set_target_properties(far_client_receiver_test PROPERTIES
  CROSSCOMPILING_EMULATOR "${PROJECT_SOURCE_DIR}/deploy/netns-run.sh")
gtest_discover_tests(far_client_receiver_test PROPERTIES LABELS unit DISCOVERY_TIMEOUT 60)
