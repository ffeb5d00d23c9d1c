#include "far/scenes/scenes.h"

#include <algorithm>
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "far/base/thread_pool.h"
#include "far/io/mesh_io.h"
#include "far/model/scene.h"
#include "far/pairs/exact_stage.h"

namespace far::scenes {
namespace {

int64_t Triangles(const std::vector<SceneObject>& objects) {
  int64_t total = 0;
  for (const SceneObject& object : objects) total += object.mesh.num_triangles();
  return total;
}

const SceneObject* FindObject(const std::vector<SceneObject>& objects, uint32_t id) {
  for (const SceneObject& object : objects) {
    if (object.id == id) return &object;
  }
  return nullptr;
}

Mesh ReadBunny() {
  Result<Mesh> bunny = ReadMesh(FAR_BUNNY_OBJ);
  EXPECT_TRUE(bunny.ok()) << ToString(bunny.error());
  return bunny.ok() ? std::move(*bunny) : Mesh();
}

// Every undirected edge is used by exactly two triangles, once in each direction.
::testing::AssertionResult IsClosed(const Mesh& mesh) {
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const TriangleIndices& t : mesh.triangles) {
    for (int e = 0; e < 3; ++e) ++directed[{t[e], t[(e + 1) % 3]}];
  }
  for (const auto& [edge, count] : directed) {
    const auto twin = directed.find({edge.second, edge.first});
    if (count != 1 || twin == directed.end() || twin->second != 1) {
      return ::testing::AssertionFailure()
             << "edge " << edge.first << "-" << edge.second << " used " << count
             << " times, its reverse " << (twin == directed.end() ? 0 : twin->second) << " times";
    }
  }
  return ::testing::AssertionSuccess();
}

::testing::AssertionResult SameObject(const SceneObject& a, const SceneObject& b) {
  if (a.id != b.id || a.mesh_path != b.mesh_path || a.motion != b.motion ||
      a.mesh.p_MV != b.mesh.p_MV || a.mesh.triangles != b.mesh.triangles ||
      a.X_WO.translation != b.X_WO.translation ||
      a.X_WO.rotation.coeffs() != b.X_WO.rotation.coeffs()) {
    return ::testing::AssertionFailure() << "object " << a.id << " differs";
  }
  return ::testing::AssertionSuccess();
}

// Exactly equal: same objects, same updates, bit for bit.
::testing::AssertionResult SameScene(const Scene& a, const Scene& b) {
  if (a.objects.size() != b.objects.size() || a.frames.size() != b.frames.size()) {
    return ::testing::AssertionFailure() << "different numbers of objects or frames";
  }
  for (size_t i = 0; i < a.objects.size(); ++i) {
    if (auto same = SameObject(a.objects[i], b.objects[i]); !same) return same;
  }
  for (size_t f = 0; f < a.frames.size(); ++f) {
    const FrameUpdate &x = a.frames[f], &y = b.frames[f];
    bool same = x.removals == y.removals && x.poses.size() == y.poses.size() &&
                x.vertices.size() == y.vertices.size() && x.additions.size() == y.additions.size();
    for (size_t i = 0; same && i < x.poses.size(); ++i) {
      same = x.poses[i].first == y.poses[i].first &&
             x.poses[i].second.translation == y.poses[i].second.translation &&
             x.poses[i].second.rotation.coeffs() == y.poses[i].second.rotation.coeffs();
    }
    for (size_t i = 0; same && i < x.vertices.size(); ++i) {
      same = x.vertices[i].first == y.vertices[i].first &&
             x.vertices[i].second.p_MV == y.vertices[i].second.p_MV &&
             x.vertices[i].second.triangles == y.vertices[i].second.triangles;
    }
    for (size_t i = 0; same && i < x.additions.size(); ++i) {
      same = static_cast<bool>(SameObject(x.additions[i], y.additions[i]));
    }
    if (!same) return ::testing::AssertionFailure() << "frame " << f + 1 << " differs";
  }
  return ::testing::AssertionSuccess();
}

using IdPair = std::pair<uint32_t, uint32_t>;

// The object pairs in contact at each frame (0 = the scene's objects), by the brute-force
// reference on the objects alive at that frame.
std::vector<std::set<IdPair>> ContactsPerFrame(const Scene& scene) {
  ThreadPool pool(2);
  std::map<uint32_t, SceneObject> alive;
  for (const SceneObject& object : scene.objects) alive[object.id] = object;
  std::vector<std::set<IdPair>> per_frame;
  for (size_t f = 0; f <= scene.frames.size(); ++f) {
    if (f > 0) {
      const FrameUpdate& frame = scene.frames[f - 1];
      for (uint32_t id : frame.removals) alive.erase(id);
      for (const SceneObject& object : frame.additions) alive[object.id] = object;
      for (const auto& [id, X_WO] : frame.poses) alive[id].X_WO = X_WO;
      for (const auto& [id, mesh] : frame.vertices) alive[id].mesh.p_MV = mesh.p_MV;
    }
    std::vector<std::vector<Eigen::Vector3d>> p_WV;
    for (const auto& [id, object] : alive) {
      const Eigen::Isometry3d X_WO = object.X_WO.ToIsometry();
      std::vector<Eigen::Vector3d>& points = p_WV.emplace_back();
      for (const Eigen::Vector3d& p_OV : object.mesh.p_MV) points.push_back(X_WO * p_OV);
    }
    std::vector<WorldObjectView> views;
    std::vector<uint32_t> ids;  // by slot
    for (const auto& [id, object] : alive) {
      views.push_back({p_WV[views.size()], object.mesh.triangles});
      ids.push_back(id);
    }
    std::set<IdPair> pairs;
    for (const SlotContact& c : BruteForceReference(views, std::nullopt, pool).contacts)
      pairs.emplace(ids[Index(c.object_a)], ids[Index(c.object_b)]);
    per_frame.push_back(std::move(pairs));
  }
  return per_frame;
}

int FramesWithContacts(const std::vector<std::set<IdPair>>& contacts) {
  return static_cast<int>(
      std::count_if(contacts.begin(), contacts.end(), [](const auto& c) { return !c.empty(); }));
}

TEST(ScenesTest, RefineMeshKeepsTheBunnyClosedWithNSquaredTrianglesPerTriangle) {
  const Mesh bunny = ReadBunny();
  ASSERT_EQ(bunny.num_triangles(), 3674);
  ASSERT_TRUE(IsClosed(bunny));
  const int edges = bunny.num_triangles() * 3 / 2;
  for (int n : {1, 2, 3, 5}) {
    SCOPED_TRACE("n = " + std::to_string(n));
    const Mesh fine = RefineMesh(bunny, n);
    EXPECT_EQ(fine.num_triangles(), n * n * 3674);
    EXPECT_EQ(fine.num_vertices(), bunny.num_vertices() + edges * (n - 1) +
                                       bunny.num_triangles() * (n - 1) * (n - 2) / 2);
    EXPECT_TRUE(IsClosed(fine));
    EXPECT_TRUE(ValidateMesh(fine).ok());
  }
  EXPECT_EQ(RefineMesh(bunny, 5).num_triangles(), 91850);
}

TEST(ScenesTest, RefineMeshKeepsTheSurfaceAndTheOrientation) {
  Mesh triangle;
  triangle.p_MV = {{0, 0, 0}, {3, 0, 0}, {0, 3, 0}};
  triangle.triangles = {{0, 1, 2}};
  const Mesh fine = RefineMesh(triangle, 3);
  ASSERT_EQ(fine.num_triangles(), 9);
  for (const TriangleIndices& t : fine.triangles) {
    const Eigen::Vector3d n =
        (fine.p_MV[t[1]] - fine.p_MV[t[0]]).cross(fine.p_MV[t[2]] - fine.p_MV[t[0]]);
    EXPECT_NEAR(n.z(), 1.0, 1e-12);  // area 1/2 each, facing +z like the parent
  }
  for (const Eigen::Vector3d& p : fine.p_MV) EXPECT_EQ(p.z(), 0.0);
}

TEST(PaperScenesTest, LeavesHas150DeformableLeavesAndAtLeast40kTriangles) {
  const Scene scene = PaperLeavesScene(7, 3);
  ASSERT_TRUE(ValidateScene(scene).ok()) << ToString(ValidateScene(scene).error());
  ASSERT_EQ(scene.objects.size(), 151u);
  EXPECT_GE(Triangles(scene.objects), 40000);
  EXPECT_EQ(scene.objects[0].motion, Motion::kStatic);
  for (size_t i = 1; i < scene.objects.size(); ++i)
    EXPECT_EQ(scene.objects[i].motion, Motion::kDeformable);
  ASSERT_EQ(scene.frames.size(), 2u);
  for (const FrameUpdate& frame : scene.frames) {
    EXPECT_TRUE(frame.poses.empty() && frame.additions.empty() && frame.removals.empty());
    std::set<uint32_t> ids;
    for (const auto& [id, mesh] : frame.vertices) ids.insert(id);
    EXPECT_EQ(ids.size(), 150u);  // every leaf, every frame
    EXPECT_EQ(frame.vertices.size(), 150u);
  }
  // The leaves move.
  EXPECT_NE(scene.frames[0].vertices[0].second.p_MV, scene.objects[1].mesh.p_MV);
}

TEST(PaperScenesTest, BreakingHasBigObjectsAndOneBreakThenPosesOnly) {
  const Scene scene = BreakingScene(7, 8);
  ASSERT_TRUE(ValidateScene(scene).ok()) << ToString(ValidateScene(scene).error());
  ASSERT_EQ(scene.objects.size(), 2u);
  const SceneObject* ground = FindObject(scene.objects, 1);
  const SceneObject* vase = FindObject(scene.objects, 2);
  ASSERT_TRUE(ground && vase);
  EXPECT_EQ(ground->motion, Motion::kStatic);
  EXPECT_GE(ground->mesh.num_triangles(), 100000);
  EXPECT_EQ(vase->motion, Motion::kRigid);
  EXPECT_GE(vase->mesh.num_triangles(), 35000);
  ASSERT_EQ(scene.frames.size(), 7u);
  int breaks_at = -1;
  for (size_t f = 0; f < scene.frames.size(); ++f) {
    const FrameUpdate& frame = scene.frames[f];
    EXPECT_TRUE(frame.vertices.empty());
    if (!frame.removals.empty() || !frame.additions.empty()) {
      ASSERT_EQ(breaks_at, -1) << "a second break at frame " << f + 1;
      breaks_at = static_cast<int>(f);
      EXPECT_EQ(frame.removals, std::vector<uint32_t>{2});
      EXPECT_GE(frame.additions.size(), 8u);
      EXPECT_TRUE(frame.poses.empty());
      int64_t pieces = 0;
      for (const SceneObject& piece : frame.additions) {
        EXPECT_EQ(piece.motion, Motion::kRigid);
        pieces += piece.mesh.num_triangles();
      }
      EXPECT_GE(pieces, vase->mesh.num_triangles());  // every vase triangle, plus the fans
    } else if (breaks_at < 0) {
      ASSERT_EQ(frame.poses.size(), 1u);
      EXPECT_EQ(frame.poses[0].first, 2u);
    } else {
      EXPECT_EQ(frame.poses.size(), scene.frames[static_cast<size_t>(breaks_at)].additions.size());
    }
  }
  EXPECT_GT(breaks_at, 0);  // in the middle: poses before it
  EXPECT_LT(breaks_at, 6);  // and after it
}

TEST(PaperScenesTest, BunniesAreTwoRefinedBunniesInRigidRelativeMotion) {
  const Scene scene = BunniesScene(ReadBunny(), 5, 7, 3);
  ASSERT_TRUE(ValidateScene(scene).ok()) << ToString(ValidateScene(scene).error());
  ASSERT_EQ(scene.objects.size(), 2u);
  EXPECT_EQ(scene.objects[0].motion, Motion::kStatic);
  EXPECT_EQ(scene.objects[1].motion, Motion::kRigid);
  for (const SceneObject& object : scene.objects) {
    EXPECT_GE(object.mesh.num_triangles(), 60000);
    EXPECT_EQ(object.mesh.num_triangles(), 91850);
  }
  ASSERT_EQ(scene.frames.size(), 2u);
  for (const FrameUpdate& frame : scene.frames) {
    EXPECT_TRUE(frame.vertices.empty() && frame.additions.empty() && frame.removals.empty());
    ASSERT_EQ(frame.poses.size(), 1u);
    EXPECT_EQ(frame.poses[0].first, scene.objects[1].id);
  }
}

TEST(PaperScenesTest, ScalingIsWithinTenPercentOfTheTargetAtEverySize) {
  for (int target : {5000, 20000, 100000, 300000}) {
    SCOPED_TRACE("target " + std::to_string(target));
    const Scene scene = ScalingScene(7, target, 2);
    ASSERT_TRUE(ValidateScene(scene).ok()) << ToString(ValidateScene(scene).error());
    const int64_t total = Triangles(scene.objects);
    EXPECT_NEAR(static_cast<double>(total), target, 0.1 * target);
    std::map<Motion, int64_t> by_motion;
    for (const SceneObject& object : scene.objects)
      by_motion[object.motion] += object.mesh.num_triangles();
    // The same mix at every size.
    EXPECT_NEAR(by_motion[Motion::kStatic] / static_cast<double>(total), 0.3, 0.1);
    EXPECT_NEAR(by_motion[Motion::kRigid] / static_cast<double>(total), 0.4, 0.1);
    EXPECT_NEAR(by_motion[Motion::kDeformable] / static_cast<double>(total), 0.3, 0.1);
    ASSERT_EQ(scene.frames.size(), 1u);
    size_t rigid = 0, deformable = 0;
    for (const SceneObject& object : scene.objects) {
      rigid += object.motion == Motion::kRigid;
      deformable += object.motion == Motion::kDeformable;
    }
    EXPECT_EQ(scene.frames[0].poses.size(), rigid);
    EXPECT_EQ(scene.frames[0].vertices.size(), deformable);
  }
  // More objects as well as finer ones.
  EXPECT_GT(ScalingScene(7, 300000, 1).objects.size(), 3 * ScalingScene(7, 5000, 1).objects.size());
}

TEST(PaperScenesTest, SameSeedSameScene) {
  const Mesh bunny = ReadBunny();
  EXPECT_TRUE(SameScene(PaperLeavesScene(3, 4, 20, 4, 2000), PaperLeavesScene(3, 4, 20, 4, 2000)));
  EXPECT_TRUE(SameScene(BreakingScene(3, 6, 2000, 1000, 8), BreakingScene(3, 6, 2000, 1000, 8)));
  EXPECT_TRUE(SameScene(BunniesScene(bunny, 1, 3, 4), BunniesScene(bunny, 1, 3, 4)));
  EXPECT_TRUE(SameScene(ScalingScene(3, 5000, 4), ScalingScene(3, 5000, 4)));
  // And the seed matters.
  EXPECT_FALSE(SameScene(PaperLeavesScene(3, 4, 20, 4, 2000), PaperLeavesScene(4, 4, 20, 4, 2000)));
  EXPECT_FALSE(SameScene(BreakingScene(3, 6, 2000, 1000, 8), BreakingScene(4, 6, 2000, 1000, 8)));
  EXPECT_FALSE(SameScene(BunniesScene(bunny, 1, 3, 4), BunniesScene(bunny, 1, 4, 4)));
  EXPECT_FALSE(SameScene(ScalingScene(3, 5000, 4), ScalingScene(4, 5000, 4)));
}

// Culling studies need something to find: contacts at most frames, of the kinds the workload
// promises. Small instances, checked by brute force.

TEST(PaperScenesTest, LeavesTouchBranchesAndEachOtherAtMostFrames) {
  const int num_leaves = 20;
  const Scene scene = PaperLeavesScene(7, 20, num_leaves, 4, 2000);
  ASSERT_TRUE(ValidateScene(scene).ok());
  const auto contacts = ContactsPerFrame(scene);
  EXPECT_GE(FramesWithContacts(contacts), 18);
  int leaf_tree = 0, leaf_leaf = 0;
  for (const auto& pairs : contacts) {
    for (const auto& [a, b] : pairs) (a == 0 ? leaf_tree : leaf_leaf) += 1;
  }
  // Summed over frames: on average several leaves on branches and a pair crossing per frame.
  EXPECT_GE(leaf_tree, 3 * 20);
  EXPECT_GE(leaf_leaf, 20);
}

TEST(PaperScenesTest, BreakingTouchesTheGroundBeforeAndAfterTheBreak) {
  const Scene scene = BreakingScene(7, 12, 5000, 2000, 8);
  ASSERT_TRUE(ValidateScene(scene).ok());
  const auto contacts = ContactsPerFrame(scene);
  // Every frame: the vase, then every fragment, crosses the ground.
  for (size_t f = 0; f < contacts.size(); ++f) {
    SCOPED_TRACE("frame " + std::to_string(f));
    std::set<uint32_t> on_ground;
    for (const auto& [a, b] : contacts[f]) {
      if (a == 1) on_ground.insert(b);
    }
    if (f < 6) {
      EXPECT_EQ(on_ground, std::set<uint32_t>{2});
    } else if (f > 6) {
      EXPECT_EQ(on_ground.size(), 8u);
    }
  }
  // At the break the pieces touch each other.
  EXPECT_TRUE(std::any_of(contacts[6].begin(), contacts[6].end(),
                          [](const IdPair& pair) { return pair.first > 2; }));
}

TEST(PaperScenesTest, BunniesInterpenetrateAtEveryFrame) {
  const Scene scene = BunniesScene(ReadBunny(), 1, 7, 8);
  ASSERT_TRUE(ValidateScene(scene).ok());
  EXPECT_EQ(FramesWithContacts(ContactsPerFrame(scene)), 8);
}

TEST(PaperScenesTest, ScalingHasContactsAtEveryFrame) {
  const Scene scene = ScalingScene(7, 5000, 12);
  ASSERT_TRUE(ValidateScene(scene).ok());
  const auto contacts = ContactsPerFrame(scene);
  EXPECT_EQ(FramesWithContacts(contacts), 12);
  // The rolling spheres (ids 2, 4, ...) touch the ground at every frame.
  for (const auto& pairs : contacts) {
    EXPECT_TRUE(pairs.contains({1, 2}));
    EXPECT_TRUE(pairs.contains({1, 4}));
  }
  // And the cloths land on something.
  std::set<uint32_t> cloths_touching;
  for (const auto& pairs : contacts) {
    for (const auto& [a, b] : pairs) {
      if (b >= 6) cloths_touching.insert(b);
    }
  }
  EXPECT_EQ(cloths_touching.size(), 2u);
}

}  // namespace
}  // namespace far::scenes

namespace far::scenes {
namespace {

// Names say what each object is (far-client play --contacts and snapshot show them): every
// generated object has one, and a broken vase's pieces are named after it.
TEST(SceneNamesTest, EveryGeneratedObjectIsNamed) {
  std::vector<Scene> scenes = {AnimatedLeavesScene(7, 5, 2, 6), PaperLeavesScene(7, 3, 6, 2, 1000),
                               BreakingScene(7, 4, 2000, 2000, 4),
                               BunniesScene(ReadBunny(), 1, 7, 2), ScalingScene(7, 5000, 2)};
  for (const Scene& scene : scenes) {
    std::vector<const SceneObject*> objects;
    for (const SceneObject& object : scene.objects) objects.push_back(&object);
    for (const FrameUpdate& frame : scene.frames) {
      for (const SceneObject& object : frame.additions) objects.push_back(&object);
    }
    for (const SceneObject* object : objects) {
      EXPECT_FALSE(object->name.empty()) << "object " << object->id;
    }
  }
  const Scene demo = AnimatedLeavesScene(7, 5, 2, 6);
  EXPECT_EQ(demo.objects[0].name, "tree");
  EXPECT_EQ(demo.objects[1].name, "leaf-1");
  EXPECT_EQ(demo.objects.back().name, "vase");
  ASSERT_EQ(demo.frames[1].additions.size(), 4u);  // breaks at frame 6 / 3 = 2
  for (size_t k = 0; k < 4; ++k) {
    EXPECT_EQ(demo.frames[1].additions[k].name, "vase-fragment-" + std::to_string(k + 1));
  }
}

// The demo's tree is cut into short pieces (contacts mark triangles near them); the leaves
// scene of the study keeps its tree as it was, so measured results stay comparable.
TEST(SceneNamesTest, DemoTreeIsCutIntoPiecesStudyTreeIsNot) {
  const std::vector<SceneObject> study = LeavesScene(7, 3, 2, 0.0);
  EXPECT_EQ(study[0].mesh.num_triangles(), 732);
  const Scene demo = AnimatedLeavesScene(7, 3, 2, 3);
  EXPECT_EQ(demo.objects[0].mesh.num_triangles(), 4412);
  EXPECT_TRUE(IsClosed(demo.objects[0].mesh));
  EXPECT_TRUE(ValidateScene(demo).ok());
  // The same surface: every vertex of the cut tree lies within the tubes' bounds.
  Eigen::AlignedBox3d before, after;
  for (const auto& p : study[0].mesh.p_MV) before.extend(p);
  for (const auto& p : demo.objects[0].mesh.p_MV) after.extend(p);
  EXPECT_TRUE(before.isApprox(after, 1e-12));
}

}  // namespace
}  // namespace far::scenes
