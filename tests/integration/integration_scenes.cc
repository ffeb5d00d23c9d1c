#include "integration_scenes.h"

#include <cmath>
#include <sstream>

#include "daemon_process.h"
#include "raw_session.h"
#include "test_scenes.h"

#include "far/base/thread_pool.h"
#include "far/client/client.h"

namespace far::integration {

std::vector<SceneObject> ContactSoup(uint64_t seed, const Eigen::Vector3d& origin) {
  std::vector<SceneObject> objects = scenes::RandomSoup(seed, 8, 24, 1.5, 0.5, origin);
  for (SceneObject& object : objects)
    object.mesh_path = "obj_" + std::to_string(object.id) + ".obj";
  return objects;
}

std::vector<ContactPair> ReferenceContacts(const std::vector<SceneObject>& objects) {
  ThreadPool pool(2);
  return testing::ReferenceAnswer(objects, std::nullopt, pool).contacts;
}

std::vector<ContactPair> ReferenceDistancePairs(const std::vector<SceneObject>& objects,
                                                double distance) {
  ThreadPool pool(2);
  std::vector<ContactPair> pairs;
  for (const DistancePair& d : testing::ReferenceAnswer(objects, distance, pool).distance_pairs) {
    pairs.push_back(d.pair);
  }
  return pairs;
}

::testing::AssertionResult HealthyClientSteps(const std::string& name) {
  static const std::vector<SceneObject> kObjects = ContactSoup(kHealthySeed);
  static const std::vector<ContactPair> kExpected = ReferenceContacts(kObjects);
  if (kExpected.empty())
    return ::testing::AssertionFailure() << "the healthy scene has no contacts";
  auto client = client::Client::Connect(TestClientOptions(name));
  if (!client)
    return ::testing::AssertionFailure()
           << "healthy client: connect: " << far::ToString(client.error());
  Scene scene;
  scene.objects = kObjects;
  if (auto ok = (*client)->LoadScene(scene); !ok) {
    return ::testing::AssertionFailure() << "healthy client: load: " << far::ToString(ok.error());
  }
  auto result = (*client)->Step(SmallRequest());
  if (!result)
    return ::testing::AssertionFailure()
           << "healthy client: step: " << far::ToString(result.error());
  if (result->contacts != kExpected) {
    return ::testing::AssertionFailure()
           << "healthy client: contacts " << ToString(result->contacts)
           << " differ from the reference " << ToString(kExpected);
  }
  if (auto closed = (*client)->Close(); !closed) {
    return ::testing::AssertionFailure()
           << "healthy client: close: " << far::ToString(closed.error());
  }
  return ::testing::AssertionSuccess() << kExpected.size() << " contacts";
}

Mesh TriangleRow(int n) {
  Mesh mesh;
  for (int i = 0; i < n; ++i) {
    const double x = 2.0 * i;
    const auto first = static_cast<uint32_t>(mesh.p_MV.size());
    mesh.p_MV.emplace_back(x, 0.0, 0.0);
    mesh.p_MV.emplace_back(x + 1.0, 0.0, 0.0);
    mesh.p_MV.emplace_back(x, 1.0, 0.0);
    mesh.triangles.push_back({first, first + 1, first + 2});
  }
  return mesh;
}

Mesh TriangleFan(int n) {
  Mesh mesh;
  mesh.p_MV.emplace_back(0.0, 0.0, 0.0);
  for (int i = 0; i <= n; ++i) {
    const double angle = 3.0 * i / n;
    mesh.p_MV.emplace_back(std::cos(angle), std::sin(angle), 0.0);
  }
  for (uint32_t i = 1; i <= static_cast<uint32_t>(n); ++i) mesh.triangles.push_back({0, i, i + 1});
  return mesh;
}

Mesh FlatGrid(int n) {
  Mesh mesh;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) mesh.p_MV.emplace_back(double(i) / n, double(j) / n, 0.0);
  }
  const auto at = [n](int i, int j) { return static_cast<uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      mesh.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  }
  return mesh;
}

std::string ToString(const std::vector<ContactPair>& pairs, size_t limit) {
  std::ostringstream out;
  out << pairs.size() << " pairs:";
  for (size_t i = 0; i < pairs.size() && i < limit; ++i) {
    const ContactPair& p = pairs[i];
    out << " [" << p.object_a << "," << p.triangle_a << "," << p.object_b << "," << p.triangle_b
        << "]";
  }
  if (pairs.size() > limit) out << " ...";
  return out.str();
}

}  // namespace far::integration
