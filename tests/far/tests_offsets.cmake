# far_add_test(<name> <label> <sources...>) for this area.
far_add_test(far_offsets_test unit
  far/offsets/bounding_offset_test.cc
  far/offsets/obb_test.cc
  far/offsets/triangle_offsets_test.cc)
target_link_libraries(far_offsets_test PRIVATE far::offsets)
target_include_directories(far_offsets_test PRIVATE ${CMAKE_CURRENT_SOURCE_DIR})
