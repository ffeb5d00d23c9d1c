// ObjectsAtStep: a scene's frames applied up to one step, for whoever needs the state itself
// (a picture of one step) rather than the updates.

#include <algorithm>
#include <string>

#include "far/model/scene.h"

namespace far {

Result<std::vector<SceneObject>> ObjectsAtStep(const Scene& scene, size_t step) {
  if (step > scene.frames.size()) {
    return MakeError(ErrorCode::kInvalidArgument, "step " + std::to_string(step) +
                                                      ": the scene has steps 0.." +
                                                      std::to_string(scene.frames.size()));
  }
  std::vector<SceneObject> objects = scene.objects;
  const auto find = [&objects](uint32_t id) {
    return std::find_if(objects.begin(), objects.end(),
                        [id](const SceneObject& object) { return object.id == id; });
  };
  for (size_t f = 0; f < step; ++f) {
    const FrameUpdate& frame = scene.frames[f];
    for (uint32_t id : frame.removals) {
      if (auto it = find(id); it != objects.end()) objects.erase(it);
    }
    objects.insert(objects.end(), frame.additions.begin(), frame.additions.end());
    for (const auto& [id, X_WO] : frame.poses) {
      if (auto it = find(id); it != objects.end()) it->X_WO = X_WO;
    }
    for (const auto& [id, mesh] : frame.vertices) {
      if (auto it = find(id); it != objects.end()) it->mesh.p_MV = mesh.p_MV;
    }
  }
  return objects;
}

}  // namespace far
