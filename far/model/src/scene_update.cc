#include "far/model/scene_update.h"

namespace far {

uint32_t ObjectIdOf(const SceneUpdate& update) {
  return std::visit([](const auto& u) { return u.id; }, update);
}

const char* UpdateName(const SceneUpdate& update) {
  static constexpr const char* kNames[] = {"add_object", "remove_object", "set_pose",
                                           "set_vertices"};
  return kNames[update.index()];
}

}  // namespace far
