far_add_test(far_base_test unit far/thread_pool_test.cc)
target_link_libraries(far_base_test PRIVATE far::base)
