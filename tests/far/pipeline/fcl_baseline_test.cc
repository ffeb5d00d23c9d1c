// The FCL baseline (Method::kFcl) is kept across the steps of an animation, as a simulation
// using FCL keeps it: models refit, broadphase updated. It must answer what FCL itself answers:
// exactly FCL's answer on a fresh copy of each step, and the exact reference's contacts except
// where FCL's own triangle test is wrong (bench/RESULTS.md). Label unit: no GL.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/geometry.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/detail/traversal/collision/intersect.h>
#include <gtest/gtest.h>

#include "far/pipeline/pipeline.h"
#include "far/scenes/scenes.h"

namespace far {
namespace {

constexpr int kSteps = 24;

// An object alive at some step: its mesh in frame M (= O) and its pose then.
struct Body {
  uint32_t id = 0;
  Motion motion = Motion::kStatic;
  Mesh mesh;
  Pose X_WO;
};

// The pose as the pipeline (and so FCL) uses it.
Eigen::Isometry3d Isometry(const Pose& pose) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = pose.rotation.normalized().toRotationMatrix();
  X.translation() = pose.translation;
  return X;
}

Pose MakePose(const Eigen::Vector3d& p, double angle, const Eigen::Vector3d& axis) {
  return Pose{p, Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()))};
}

// A flat grid of cells x cells squares (two triangles each) over [0, w] x [0, h] at z = 0.
Mesh Grid(int cells, double w, double h) {
  Mesh mesh;
  for (int i = 0; i <= cells; ++i) {
    for (int j = 0; j <= cells; ++j) {
      mesh.p_MV.emplace_back(w * i / cells, h * j / cells, 0.0);
    }
  }
  const auto v = [&](int i, int j) { return static_cast<uint32_t>(i * (cells + 1) + j); };
  for (int i = 0; i < cells; ++i) {
    for (int j = 0; j < cells; ++j) {
      mesh.triangles.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      mesh.triangles.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  }
  return mesh;
}

Mesh Translated(Mesh mesh, const Eigen::Vector3d& offset) {
  for (auto& p : mesh.p_MV) p += offset;
  return mesh;
}

// The animation: static terrain and boulder; three deformable cloths that rise by 1.6 (their
// size is 1) while they ripple and drift, one also turning by its pose; three rigid spheres
// that fall through them while spinning, one of which is removed and later added back (same
// id, another mesh); a rigid plate, off its frame's origin, that sweeps round through two
// cloths as it turns; and a rigid sphere that breaks into six fragments (removal and
// additions) that fly apart.
class Animation {
 public:
  static constexpr uint32_t kTerrain = 1, kBoulder = 2, kCloth = 10, kSphere = 20, kBreaking = 30,
                            kFragment = 31, kPlate = 40;
  static constexpr int kBreakStep = 8;

  explicit Animation(uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    for (int i = 0; i < 3; ++i) {
      phase_[i] = 3.0 * unit(rng);
      drift_[i] = std::numbers::pi * unit(rng);
      axis_[i] = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) + Eigen::Vector3d(0, 0, 1.5);
    }
    for (auto& axis : fragment_axis_) axis = Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
    terrain_phase_ = unit(rng);
  }

  static double Time(int step) { return static_cast<double>(step) / (kSteps - 1); }

  std::vector<Body> At(int step) const {
    const double t = Time(step);
    std::vector<Body> bodies;
    bodies.push_back({kTerrain, Motion::kStatic, Terrain(), {}});
    bodies.push_back(
        {kBoulder, Motion::kStatic, scenes::SphereMesh({2.2, -2.2, 0.0}, 0.6, 8, 12), {}});
    for (int i = 0; i < 3; ++i) {
      bodies.push_back({kCloth + i, Motion::kDeformable, Cloth(i, t), ClothPose(i, t)});
    }
    for (int i = 0; i < 3; ++i) {
      if (i == 1 && step >= 9 && step <= 12) continue;  // removed, then back with a new mesh
      const bool second_life = i == 1 && step > 12;
      Mesh mesh = second_life ? scenes::SphereMesh(Eigen::Vector3d::Zero(), 0.3, 6, 10)
                              : scenes::SphereMesh(Eigen::Vector3d::Zero(), 0.35, 8, 12);
      const Eigen::Vector3d center = ClothCenterW(i, t);
      const Eigen::Vector3d p(center.x() + 0.1, center.y() - 0.1, 3.0 - 3.3 * t + 0.1 * i);
      bodies.push_back({kSphere + i, Motion::kRigid, std::move(mesh),
                        MakePose(p, 2.0 * (i + 1) * t + phase_[i], axis_[i])});
    }
    // The plate's mesh is off its frame's origin, so that turning it moves it far.
    bodies.push_back({kPlate, Motion::kRigid, Translated(Grid(6, 1.8, 0.3), {0.3, -0.15, 0.0}),
                      MakePose({0.0, 0.0, 1.0}, 4 * std::numbers::pi * t, {0.05, 0.05, 1.0})});
    if (step < kBreakStep) {
      bodies.push_back({kBreaking, Motion::kRigid, BreakingSphere(), BreakingPose(t)});
    } else {
      for (int k = 0; k < 6; ++k) {
        bodies.push_back({kFragment + k, Motion::kRigid, Fragment(k), FragmentPose(k, t)});
      }
    }
    return bodies;
  }

  // The world box of deformable object `id` at step 0.
  Eigen::AlignedBox3d OriginalBox(uint32_t id) const {
    Eigen::AlignedBox3d box;
    for (const Body& body : At(0)) {
      if (body.id != id) continue;
      const Eigen::Isometry3d X_WO = Isometry(body.X_WO);
      for (const auto& p : body.mesh.p_MV) box.extend(X_WO * p);
    }
    return box;
  }

 private:
  static Eigen::Vector3d ClothCorner(int i) {
    static constexpr double kCorners[3][2] = {{-1.7, -0.5}, {-0.3, 0.4}, {0.8, -1.1}};
    return {kCorners[i][0], kCorners[i][1], 0.0};
  }

  Mesh Terrain() const {
    Mesh mesh = Translated(Grid(16, 6.0, 6.0), {-3.0, -3.0, 0.0});
    for (auto& p : mesh.p_MV) {
      p.z() = -0.15 + 0.08 * std::sin(1.3 * p.x() + terrain_phase_) * std::cos(1.1 * p.y());
    }
    return mesh;
  }

  // Where cloth i's middle has drifted to at time t, in its frame.
  Eigen::Vector3d ClothShift(int i, double t) const {
    return {0.6 * t * std::cos(drift_[i]), 0.6 * t * std::sin(drift_[i]), 1.6 * t};
  }

  Mesh Cloth(int i, double t) const {
    Mesh mesh = Grid(10, 1.0, 1.0);
    const Eigen::Vector3d shift = ClothShift(i, t);
    for (auto& p : mesh.p_MV) {
      const double u = p.x(), v = p.y();
      const double ripple = 0.2 * std::sin(2 * std::numbers::pi * u + 3.0 * t + phase_[i]) *
                            std::sin(std::numbers::pi * v);
      const double fold = 0.5 * t * (u - 0.5) * (u - 0.5);
      p = ClothCorner(i) + Eigen::Vector3d(u, v, ripple + fold) + shift;
    }
    return mesh;
  }

  // Cloth 2 also turns about its middle; the others stay at the identity.
  Pose ClothPose(int i, double t) const {
    if (i != 2) return {};
    const Eigen::Vector3d c = ClothCorner(i) + Eigen::Vector3d(0.5, 0.5, 0.0);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.8 * t, Eigen::Vector3d::UnitZ()).matrix();
    return Pose{c - R * c, Eigen::Quaterniond(R)};
  }

  Eigen::Vector3d ClothCenterW(int i, double t) const {
    const Eigen::Vector3d c_M = ClothCorner(i) + Eigen::Vector3d(0.5, 0.5, 0.0) + ClothShift(i, t);
    return Isometry(ClothPose(i, t)) * c_M;
  }

  static Mesh BreakingSphere() { return scenes::SphereMesh(Eigen::Vector3d::Zero(), 0.5, 9, 18); }
  Pose BreakingPose(double t) const {
    return MakePose({-1.8, 1.8, 2.4 - 2.6 * t}, 1.2 * t, {1.0, 0.3, 0.2});
  }

  // Fragment k: the sphere's slices 3k..3k+2 (2 * (stacks - 1) triangles per slice, in order),
  // with its own vertices. Neighbouring fragments share edges at the break.
  static Mesh Fragment(int k) {
    const Mesh sphere = BreakingSphere();
    const size_t per_fragment = sphere.triangles.size() / 6;
    Mesh mesh;
    std::map<uint32_t, uint32_t> index;
    for (size_t t = k * per_fragment; t < (k + 1) * per_fragment; ++t) {
      TriangleIndices triangle;
      for (int c = 0; c < 3; ++c) {
        const uint32_t v = sphere.triangles[t][c];
        auto [it, added] = index.try_emplace(v, static_cast<uint32_t>(mesh.p_MV.size()));
        if (added) mesh.p_MV.push_back(sphere.p_MV[v]);
        triangle[c] = it->second;
      }
      mesh.triangles.push_back(triangle);
    }
    return mesh;
  }

  Pose FragmentPose(int k, double t) const {
    const double dt = t - Time(kBreakStep);
    const Pose X_break = BreakingPose(Time(kBreakStep));
    const double angle = 2 * std::numbers::pi * (k + 0.5) / 6;
    const Eigen::Vector3d direction(std::cos(angle), std::sin(angle), 0.3);
    const Eigen::Quaterniond spin(Eigen::AngleAxisd(3.0 * dt, fragment_axis_[k].normalized()));
    return Pose{X_break.translation + X_break.rotation * (1.5 * dt * direction) +
                    Eigen::Vector3d(0, 0, -1.2 * dt),
                (X_break.rotation * spin).normalized()};
  }

  double phase_[3], drift_[3], terrain_phase_;
  Eigen::Vector3d axis_[3], fragment_axis_[6];
};

// Applies `bodies` to a pipeline that holds `alive` (the previous step's bodies): removals,
// additions, then poses and vertices of what stayed.
void Apply(Pipeline& pipeline, std::map<uint32_t, Body>& alive, const std::vector<Body>& bodies) {
  std::set<uint32_t> now;
  for (const Body& body : bodies) now.insert(body.id);
  for (auto it = alive.begin(); it != alive.end();) {
    if (now.count(it->first)) {
      ++it;
      continue;
    }
    ASSERT_TRUE(pipeline.RemoveObject(it->first).ok());
    it = alive.erase(it);
  }
  for (const Body& body : bodies) {
    if (!alive.count(body.id)) {
      auto ok = pipeline.AddObject(body.id, body.mesh, body.motion, body.X_WO);
      ASSERT_TRUE(ok.ok()) << ToString(ok.error());
    } else if (body.motion != Motion::kStatic) {
      ASSERT_TRUE(pipeline.SetPose(body.id, body.X_WO).ok());
      if (body.motion == Motion::kDeformable) {
        ASSERT_TRUE(pipeline.SetVertices(body.id, body.mesh.p_MV).ok());
      }
    }
    alive[body.id] = body;
  }
}

StepResult StepWith(Pipeline& pipeline, Method method) {
  StepRequest request;
  request.method = method;
  auto result = pipeline.Step(request);
  EXPECT_TRUE(result.ok()) << ToString(result.error());
  return result.ok() ? std::move(*result) : StepResult{};
}

std::unique_ptr<Pipeline> MakePipeline() {
  PipelineOptions options;
  options.num_threads = 2;
  options.use_gl = false;
  auto pipeline = Pipeline::Create(options);
  EXPECT_TRUE(pipeline.ok()) << ToString(pipeline.error());
  return pipeline.ok() ? std::move(*pipeline) : nullptr;
}

std::vector<ContactPair> SymmetricDifference(const std::vector<ContactPair>& a,
                                             const std::vector<ContactPair>& b) {
  std::vector<ContactPair> out;
  std::set_symmetric_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

std::string Describe(const ContactPair& c) {
  return std::to_string(c.object_a) + "/" + std::to_string(c.triangle_a) + " - " +
         std::to_string(c.object_b) + "/" + std::to_string(c.triangle_b);
}

// FCL's own triangle test on one pair, as FCL's mesh-mesh traversal runs it: the first
// object's triangle in its frame, the second's moved into that frame by the relative transform
// (the collider passes the smaller id first).
bool FclTriangleTest(const Body& a, uint32_t triangle_a, const Body& b, uint32_t triangle_b) {
  Eigen::Matrix3d R;
  Eigen::Vector3d T;
  fcl::relativeTransform(fcl::Transform3d(Isometry(a.X_WO).matrix()),
                         fcl::Transform3d(Isometry(b.X_WO).matrix()), R, T);
  const auto& p = a.mesh.p_MV;
  const auto& q = b.mesh.p_MV;
  const TriangleIndices& s = a.mesh.triangles[triangle_a];
  const TriangleIndices& u = b.mesh.triangles[triangle_b];
  return fcl::detail::Intersect<double>::intersect_Triangle(p[s[0]], p[s[1]], p[s[2]], q[u[0]],
                                                            q[u[1]], q[u[2]], R, T);
}

// The same test on the pair's world coordinates (as bench/geometry/triangle_test_benchmark.cc).
bool FclWorldTriangleTest(const Body& a, uint32_t triangle_a, const Body& b, uint32_t triangle_b) {
  const Eigen::Isometry3d X_WA = Isometry(a.X_WO), X_WB = Isometry(b.X_WO);
  const auto& p = a.mesh.p_MV;
  const auto& q = b.mesh.p_MV;
  const TriangleIndices& s = a.mesh.triangles[triangle_a];
  const TriangleIndices& u = b.mesh.triangles[triangle_b];
  return fcl::detail::Intersect<double>::intersect_Triangle(X_WA * p[s[0]], X_WA * p[s[1]],
                                                            X_WA * p[s[2]], X_WB * q[u[0]],
                                                            X_WB * q[u[1]], X_WB * q[u[2]]);
}

// FCL alone on one step: fresh BVHModel<OBBRSS> models, fcl::collide on every object pair
// (no broadphase), smaller id first as the collider passes them.
std::vector<ContactPair> FclDirect(const std::vector<Body>& bodies) {
  std::map<uint32_t, std::unique_ptr<fcl::CollisionObjectd>> objects;
  for (const Body& body : bodies) {
    auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
    std::vector<fcl::Triangle> triangles;
    for (const auto& t : body.mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    model->beginModel();
    model->addSubModel(body.mesh.p_MV, triangles);
    model->endModel();
    const Eigen::Isometry3d X_WO = Isometry(body.X_WO);
    objects[body.id] =
        std::make_unique<fcl::CollisionObjectd>(model, X_WO.linear(), X_WO.translation());
  }
  std::vector<ContactPair> contacts;
  for (auto a = objects.begin(); a != objects.end(); ++a) {
    for (auto b = std::next(a); b != objects.end(); ++b) {
      fcl::CollisionRequestd request(std::numeric_limits<size_t>::max(), false);
      fcl::CollisionResultd result;
      fcl::collide(a->second.get(), b->second.get(), request, result);
      for (size_t i = 0; i < result.numContacts(); ++i) {
        const auto& contact = result.getContact(i);
        contacts.push_back({a->first, static_cast<uint32_t>(contact.b1), b->first,
                            static_cast<uint32_t>(contact.b2)});
      }
    }
  }
  std::sort(contacts.begin(), contacts.end());
  return contacts;
}

// Whether the two triangles have a vertex in common in the world (within rounding).
bool ShareAVertex(const Body& a, uint32_t triangle_a, const Body& b, uint32_t triangle_b) {
  for (uint32_t u : a.mesh.triangles[triangle_a]) {
    for (uint32_t v : b.mesh.triangles[triangle_b]) {
      const Eigen::Vector3d p_WU = Isometry(a.X_WO) * a.mesh.p_MV[u];
      const Eigen::Vector3d p_WV = Isometry(b.X_WO) * b.mesh.p_MV[v];
      if ((p_WU - p_WV).norm() <= 1e-12) return true;
    }
  }
  return false;
}

TEST(FclBaselineTest, KeptAcrossAnAnimationFclAnswersWhatFclAnswersOnEachStep) {
  const Animation animation(/*seed=*/8);
  auto kept = MakePipeline();
  ASSERT_NE(kept, nullptr);
  std::map<uint32_t, Body> alive;
  std::map<uint32_t, Eigen::AlignedBox3d> original_box;
  for (uint32_t id = Animation::kCloth; id < Animation::kCloth + 3; ++id) {
    original_box[id] = animation.OriginalBox(id);
  }

  int fcl_contacts = 0, exact_contacts = 0, not_one_shot = 0, not_direct = 0, unexplained = 0;
  int false_positives = 0, touching_misses = 0, world_disagreements = 0;
  int steps_beyond = 0, beyond_contacts = 0, beyond_found = 0;
  int64_t kept_tests = 0, one_shot_tests = 0;
  for (int step = 0; step < kSteps; ++step) {
    SCOPED_TRACE("step " + std::to_string(step));
    const std::vector<Body> bodies = animation.At(step);
    Apply(*kept, alive, bodies);
    if (HasFatalFailure()) return;
    const StepResult fcl = StepWith(*kept, Method::kFcl);
    const StepResult exact = StepWith(*kept, Method::kExact);
    fcl_contacts += static_cast<int>(fcl.contacts.size());
    exact_contacts += static_cast<int>(exact.contacts.size());
    const auto fcl_finds = [&](const ContactPair& c) {
      return std::binary_search(fcl.contacts.begin(), fcl.contacts.end(), c);
    };

    // FCL kept across steps answers exactly what FCL answers on a fresh copy of this step.
    auto fresh = MakePipeline();
    ASSERT_NE(fresh, nullptr);
    std::map<uint32_t, Body> fresh_alive;
    Apply(*fresh, fresh_alive, bodies);
    const StepResult one_shot = StepWith(*fresh, Method::kFcl);
    not_one_shot += static_cast<int>(SymmetricDifference(fcl.contacts, one_shot.contacts).size());
    EXPECT_EQ(fcl.contacts, one_shot.contacts) << "kept FCL differs from one-shot FCL";
    EXPECT_EQ(fcl.stats.object_pairs, one_shot.stats.object_pairs);
    const std::vector<ContactPair> direct = FclDirect(bodies);
    not_direct += static_cast<int>(SymmetricDifference(fcl.contacts, direct).size());
    EXPECT_EQ(fcl.contacts, direct) << "kept FCL differs from fcl::collide on every pair";
    kept_tests += fcl.stats.pairs_tested;
    one_shot_tests += one_shot.stats.pairs_tested;

    // Every difference from the exact answer is FCL's own triangle test being wrong: on that
    // pair alone, on the input FCL gives it, the test gives FCL's answer. A contact FCL misses
    // must moreover be a touch at a shared vertex: FCL moves the second triangle into the
    // first's frame (R = R1^T R2 is not exactly I for equal poses), which can part a shared
    // vertex by an ulp.
    for (const ContactPair& c : SymmetricDifference(fcl.contacts, exact.contacts)) {
      const bool fcl_says = fcl_finds(c);
      const Body& a = alive.at(c.object_a);
      const Body& b = alive.at(c.object_b);
      if (FclWorldTriangleTest(a, c.triangle_a, b, c.triangle_b) != fcl_says) {
        ++world_disagreements;
      }
      const bool narrowphase = FclTriangleTest(a, c.triangle_a, b, c.triangle_b) == fcl_says;
      if (narrowphase && fcl_says) {
        ++false_positives;
      } else if (narrowphase && ShareAVertex(a, c.triangle_a, b, c.triangle_b)) {
        ++touching_misses;
      } else {
        ++unexplained;
        ADD_FAILURE() << "FCL " << (fcl_says ? "reports" : "misses") << " contact " << Describe(c)
                      << (narrowphase ? ", a pair without a shared vertex"
                          : fcl_says  ? ", which its own triangle test rejects"
                                      : ", which its own triangle test finds");
      }
    }

    // The case of issue 8: a rigid object meets a deformable one where it has moved to, away
    // from where its vertices were at the start.
    bool beyond = false;
    for (const ContactPair& c : exact.contacts) {
      for (auto [deformable, triangle, other] :
           {std::tuple{c.object_a, c.triangle_a, c.object_b},
            std::tuple{c.object_b, c.triangle_b, c.object_a}}) {
        const Body& d = alive.at(deformable);
        if (d.motion != Motion::kDeformable || alive.at(other).motion != Motion::kRigid) continue;
        Eigen::AlignedBox3d box;
        for (uint32_t v : d.mesh.triangles[triangle]) box.extend(Isometry(d.X_WO) * d.mesh.p_MV[v]);
        if (box.intersects(original_box.at(deformable))) continue;
        beyond = true;
        ++beyond_contacts;
        beyond_found += fcl_finds(c) ? 1 : 0;
      }
    }
    steps_beyond += beyond ? 1 : 0;

    // pairs_tested counts FCL's triangle tests: at least one per reported contact.
    EXPECT_GE(fcl.stats.pairs_tested, static_cast<int64_t>(fcl.contacts.size()));
    EXPECT_LE(fcl.stats.pairs_tested, fcl.stats.pairs_considered);
    EXPECT_GE(fcl.stats.object_pairs, static_cast<int64_t>(fcl.object_pairs.size()));
  }
  std::printf(
      "contacts: fcl %d, exact %d; kept fcl differs from one-shot fcl on %d, from fcl::collide "
      "on every pair on %d; fcl - exact differences "
      "from FCL's triangle test: %d false positives, %d misses of touching pairs (FCL's test on "
      "world coordinates disagrees with FCL on %d); unexplained %d; rigid - deformable contacts "
      "beyond the deformable's original box: %d at %d steps, fcl finds %d; FCL triangle tests: "
      "kept %lld, one-shot %lld\n",
      fcl_contacts, exact_contacts, not_one_shot, not_direct, false_positives, touching_misses,
      world_disagreements, unexplained, beyond_contacts, steps_beyond, beyond_found,
      static_cast<long long>(kept_tests), static_cast<long long>(one_shot_tests));
  EXPECT_EQ(unexplained, 0);
  EXPECT_EQ(not_one_shot, 0);
  EXPECT_EQ(not_direct, 0);
  EXPECT_GE(steps_beyond, 3) << "the animation does not exercise issue 8";
  EXPECT_EQ(beyond_found, beyond_contacts);
  EXPECT_GT(exact_contacts, 0);
}

// Three spheres: a and b intersect; the boxes of a and d overlap but the spheres do not; c is
// far away. FCL's broadphase passes two object pairs; only a - b has contacts.
TEST(FclBaselineTest, StatsCountBroadphasePairsAndTriangleTests) {
  auto pipeline = MakePipeline();
  ASSERT_NE(pipeline, nullptr);
  const Mesh sphere = scenes::SphereMesh(Eigen::Vector3d::Zero(), 1.0, 8, 12);
  const Mesh small = scenes::SphereMesh(Eigen::Vector3d::Zero(), 0.8, 8, 12);
  ASSERT_TRUE(pipeline->AddObject(1, sphere, Motion::kRigid, {}).ok());
  ASSERT_TRUE(pipeline->AddObject(2, sphere, Motion::kRigid, Pose{{1.5, 0.0, 0.0}}).ok());
  ASSERT_TRUE(pipeline->AddObject(3, sphere, Motion::kRigid, Pose{{10.0, 0.0, 0.0}}).ok());
  ASSERT_TRUE(pipeline->AddObject(4, small, Motion::kRigid, Pose{{-1.6, 1.6, 0.0}}).ok());
  const StepResult fcl = StepWith(*pipeline, Method::kFcl);
  ASSERT_FALSE(fcl.contacts.empty());
  EXPECT_EQ(fcl.object_pairs, (std::vector<ObjectPair>{{1, 2}}));
  EXPECT_EQ(fcl.stats.object_pairs, 2);  // 1 - 2 and 1 - 4
  EXPECT_GE(fcl.stats.pairs_tested, static_cast<int64_t>(fcl.contacts.size()));
  // Every triangle pair of the two candidate object pairs is considered.
  const int64_t n = sphere.num_triangles(), m = small.num_triangles();
  EXPECT_EQ(fcl.stats.pairs_considered, n * n + n * m);
  EXPECT_LE(fcl.stats.pairs_tested, fcl.stats.pairs_considered);
  EXPECT_EQ(fcl.contacts, StepWith(*pipeline, Method::kExact).contacts);
}

}  // namespace
}  // namespace far
