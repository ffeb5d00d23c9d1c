# far::client's logic that needs no daemon: how it finds one (discovery.h), and the receiving
# thread its Clients share (client/src/shared_receiver.h, over LCM's in-process memq://).
far_add_test(far_client_test unit client/discovery_test.cc client/shared_receiver_test.cc)
target_link_libraries(far_client_test PRIVATE far::client far::protocol)
target_include_directories(far_client_test PRIVATE ${PROJECT_SOURCE_DIR}/client/src)
