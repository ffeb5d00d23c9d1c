# far_add_test(<name> <label> <sources...>) for this area.
far_add_test(far_io_test unit
  far/io/obj_reader_test.cc
  far/io/ply_reader_test.cc
  far/io/stl_reader_test.cc
  far/io/mesh_io_test.cc
  far/io/scene_io_test.cc)
target_link_libraries(far_io_test PRIVATE far::io)
target_compile_definitions(far_io_test PRIVATE FAR_TEST_DATA_DIR="${PROJECT_SOURCE_DIR}/tests/data")
