// Fuzz target stl_reader: far::ReadStl on any bytes (ascii and binary, and the ambiguity
// between them). Oracles besides the sanitizers: an accepted mesh is valid and has three
// unshared vertices per facet (STL's are never welded). No write-back check: WriteStl rounds to
// float32 by design.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_input.h"

#include "far/io/mesh_io.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto mesh = far::ReadStl(bytes, "fuzz.stl");
  if (!mesh) return 0;
  FAR_FUZZ_CHECK(far::ValidateMesh(*mesh).ok());
  FAR_FUZZ_CHECK(mesh->p_MV.size() == 3 * mesh->triangles.size());
  for (size_t t = 0; t < mesh->triangles.size(); ++t) {
    const uint32_t first = static_cast<uint32_t>(3 * t);
    FAR_FUZZ_CHECK((mesh->triangles[t] == far::TriangleIndices{first, first + 1, first + 2}));
  }
  return 0;
}
