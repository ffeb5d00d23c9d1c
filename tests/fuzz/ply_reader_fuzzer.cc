// Fuzz target ply_reader: far::ReadPly on any bytes (ascii, binary little- and big-endian).
// Oracles besides the sanitizers: an accepted mesh is valid and WritePly gives it back exactly.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "mesh_round_trip.h"

#include "far/io/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto mesh = far::ReadPly(bytes, "fuzz.ply");
  if (mesh) far::fuzz::CheckAcceptedMesh(*mesh, ".ply");
  return 0;
}
