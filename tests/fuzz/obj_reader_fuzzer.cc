// Fuzz target obj_reader: far::ReadObj on any bytes (mesh files of scenes, far-client collide).
// Oracles besides the sanitizers: an accepted mesh is valid and WriteObj gives it back exactly.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "mesh_round_trip.h"

#include "far/io/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto mesh = far::ReadObj(bytes, "fuzz.obj");
  if (mesh) far::fuzz::CheckAcceptedMesh(*mesh, ".obj");
  return 0;
}
