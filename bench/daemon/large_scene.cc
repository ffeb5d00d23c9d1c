#include "large_scene.h"

#include "far/scenes/scenes.h"

namespace far::study {

Scene LargestScene(int64_t max_triangles) {
  Scene scene = scenes::ScalingScene(29, static_cast<int>(max_triangles * 0.97), 1);
  scene.frames.clear();
  return scene;
}

int64_t TriangleCount(const Scene& scene) {
  int64_t count = 0;
  for (const SceneObject& object : scene.objects) count += object.mesh.triangles.size();
  return count;
}

int64_t VertexCount(const Scene& scene) {
  int64_t count = 0;
  for (const SceneObject& object : scene.objects) count += object.mesh.p_MV.size();
  return count;
}

Result<void> UploadInParts(client::Client& client, const Scene& scene, uint64_t ring_bytes) {
  StepRequest drain;
  drain.method = Method::kAabb;
  drain.output = Output::kObjectPcs;
  uint64_t written = 0;
  for (const SceneObject& object : scene.objects) {
    // An add_object record: its vertices (3 doubles) and triangles (3 uint32) and a header.
    const uint64_t bytes = object.mesh.p_MV.size() * 24 + object.mesh.triangles.size() * 12 + 256;
    if (written > 0 && written + bytes > ring_bytes / 2) {
      if (auto stepped = client.Step(drain); !stepped) return stepped.error();
      written = 0;
    }
    if (auto ok = client.AddObject(object.id, object.mesh, object.motion, object.X_WO); !ok)
      return ok;
    written += bytes;
  }
  if (auto stepped = client.Step(drain); !stepped) return stepped.error();
  return {};
}

}  // namespace far::study
