# far_add_test(<name> <label> <sources...>) for the protocol area: LCM messages, validation,
# session authentication, shared-memory segment and rings. Unit tests only: in-process, no
# network (memq:// at most), anonymous shm segments, local sockets in temporary directories.
far_add_test(far_protocol_test unit
  protocol/ring_layout_test.cc
  protocol/ring_test.cc
  protocol/ring_records_test.cc
  protocol/message_test.cc
  protocol/message_validate_test.cc
  protocol/session_auth_test.cc
  protocol/convert_test.cc
  protocol/shm_segment_test.cc protocol/local_socket_test.cc
  protocol/shm_reply_test.cc
  protocol/lcm_bus_test.cc
  protocol/lcm_log_test.cc
  protocol/recording_test.cc)
# far_lcm_eventlog: LCM's own log reader and writer, to check far's log files against them.
target_link_libraries(far_protocol_test PRIVATE far::protocol far_lcm_eventlog)
