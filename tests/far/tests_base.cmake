# far::base: the thread pool, the assert macros, the names schedulers give GPUs, timer slack.
far_add_test(far_base_test unit far/base/thread_pool_test.cc far/base/assert_test.cc
             far/base/gpu_identity_test.cc far/base/timer_slack_test.cc)
target_link_libraries(far_base_test PRIVATE far::base)
