# far_add_area(io <sources...>) and this area's dependencies.
# far_io: strict mesh readers/writers (OBJ, PLY, STL) and the far-scene/1 JSON scene format.
far_add_area(io
  src/io/io_util.cc
  src/io/mesh_io.cc
  src/io/mesh_writers.cc
  src/io/obj_reader.cc
  src/io/ply_reader.cc
  src/io/stl_reader.cc
  src/io/scene.cc
  src/io/scene_io.cc)
# Eigen is public (Mesh, Pose); nlohmann_json stays an implementation detail.
target_link_libraries(far_io PUBLIC Eigen3::Eigen PRIVATE nlohmann_json::nlohmann_json)
