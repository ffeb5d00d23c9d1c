// Fuzz target scene_reader: far::ParseScene on any bytes, the `far-scene/1` JSON reader that
// far-client collide/play and far-study run on scene files. Mesh paths resolve against
// tests/data/scenes/example (FAR_FUZZ_SCENE_DIR), so a fuzzed scene can load that scene's
// real OBJ, PLY and STL files. Oracle besides the sanitizers: an accepted scene is valid
// (ValidateScene, the rule the pipeline and WriteScene apply again).

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_input.h"

#include "far/io/scene_io.h"
#include "far/model/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view json(reinterpret_cast<const char*>(data), size);
  auto scene = far::ParseScene(json, FAR_FUZZ_SCENE_DIR);
  if (scene) FAR_FUZZ_CHECK(far::ValidateScene(*scene).ok());
  return 0;
}
