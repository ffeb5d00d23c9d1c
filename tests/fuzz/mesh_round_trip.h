#pragma once

// The mesh readers' second oracle, shared by the OBJ and PLY targets: a mesh a reader accepted
// is valid, and the matching writer (documented to round-trip exactly) gives it back unchanged.

#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <string>

#include "fuzz_input.h"

#include "far/io/mesh_io.h"
#include "far/model/mesh.h"

namespace far::fuzz {

inline bool SameMesh(const Mesh& a, const Mesh& b) {
  if (a.p_MV.size() != b.p_MV.size() || a.triangles != b.triangles) return false;
  // Bitwise: -0.0 must stay -0.0.
  return std::memcmp(a.p_MV.data(), b.p_MV.data(), a.p_MV.size() * sizeof(a.p_MV[0])) == 0;
}

/// Checks `mesh` (accepted by a reader): ValidateMesh, then a write and read back through a file
/// with `extension` (".obj" or ".ply") in this process's temporary folder.
inline void CheckAcceptedMesh(const Mesh& mesh, const char* extension) {
  FAR_FUZZ_CHECK(ValidateMesh(mesh).ok());
  static const std::filesystem::path path =
      std::filesystem::temp_directory_path() /
      ("far-fuzz-" + std::to_string(getpid()) + "-mesh" + extension);
  FAR_FUZZ_CHECK(WriteMesh(mesh, path).ok());
  auto again = ReadMesh(path);
  FAR_FUZZ_CHECK(again.ok());
  FAR_FUZZ_CHECK(SameMesh(mesh, *again));
}

}  // namespace far::fuzz
