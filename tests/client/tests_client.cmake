# far::client's logic that needs no daemon: how it finds one (discovery.h).
far_add_test(far_client_test unit client/discovery_test.cc)
target_link_libraries(far_client_test PRIVATE far::client)
