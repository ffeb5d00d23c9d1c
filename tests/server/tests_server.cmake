find_package(spdlog REQUIRED)
far_add_test(far_server_test unit server/rate_limiter_test.cc server/daemon_config_test.cc
             server/active_sessions_test.cc
             server/deadline_memory_test.cc server/socket_server_test.cc
             server/step_cpu_meter_test.cc server/log_limiter_test.cc
             server/step_ledger_test.cc server/metrics_test.cc
             server/gpu_cost_cache_test.cc)
target_link_libraries(far_server_test PRIVATE far_server_core spdlog::spdlog)
