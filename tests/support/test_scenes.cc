#include "test_scenes.h"

#include "far/model/slot_ids.h"

namespace far::testing {

WorldScene PlaceInWorld(const std::vector<SceneObject>& objects) {
  WorldScene world;
  world.p_WV.reserve(objects.size());
  for (const SceneObject& object : objects) {
    const Eigen::Isometry3d X = object.X_WO.ToIsometry();
    std::vector<Eigen::Vector3d> points;
    points.reserve(object.mesh.p_MV.size());
    // As the pipeline places objects: tiny world coordinates are 0.
    for (const auto& p : object.mesh.p_MV) points.push_back(WorldVertex(X, p));
    world.p_WV.push_back(std::move(points));
  }
  for (size_t i = 0; i < objects.size(); ++i) {
    world.views.push_back({world.p_WV[i], objects[i].mesh.triangles});
    world.ids.push_back(objects[i].id);
  }
  return world;
}

ReferencePairs ReferenceAnswer(const std::vector<SceneObject>& objects,
                               std::optional<double> distance, ThreadPool& pool) {
  const WorldScene world = PlaceInWorld(objects);
  const ExactResult exact = BruteForceReference(world.views, distance, pool);
  const SlotIds ids(world.ids);
  return {ids.WithIds(exact.contacts), ids.WithIds(exact.distance_pairs)};
}

std::vector<SceneObject> Transformed(std::vector<SceneObject> objects, const Eigen::Isometry3d& X) {
  for (SceneObject& object : objects) {
    const Eigen::Isometry3d X_new = X * object.X_WO.ToIsometry();
    object.X_WO.translation = X_new.translation();
    object.X_WO.rotation = Eigen::Quaterniond(X_new.linear()).normalized();
  }
  return objects;
}

Mesh StackedTriangles(int n, double z0, double dz) {
  Mesh mesh;
  for (int i = 0; i < n; ++i) {
    const double z = z0 + i * dz;
    const auto first = static_cast<uint32_t>(mesh.p_MV.size());
    mesh.p_MV.insert(mesh.p_MV.end(), {{0, 0, z}, {1, 0, z}, {0, 1, z}});
    mesh.triangles.push_back({first, first + 1, first + 2});
  }
  return mesh;
}

}  // namespace far::testing
