#pragma once

// The rules of a scene, in one place. Scene files (ValidateScene), the daemon (a session's
// update ring) and far::Pipeline all check their updates here:
//   add_object     the id is not alive; the mesh is valid (ValidateMesh); the pose is valid;
//                  the scene stays within its SceneLimits;
//   remove_object  the id is alive;
//   set_pose       the id is alive and its object is not static; the pose is valid (CheckPose);
//   set_vertices   the id is alive and its object is deformable; as many vertices as its mesh,
//                  every one finite.
// Updates are checked in batches, all-or-nothing: a Batch sees its own earlier updates (an
// object added, then posed), and nothing changes until Commit.

#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <string>

#include <Eigen/Core>

#include "far/base/result.h"
#include "far/model/mesh.h"
#include "far/model/pose.h"
#include "far/model/scene_budget.h"
#include "far/model/scene_update.h"

namespace far {

/// Budgets a scene must stay within (a daemon session's are configured; the default is none).
struct SceneLimits {
  int64_t max_objects = std::numeric_limits<int64_t>::max();
  int64_t max_triangles = std::numeric_limits<int64_t>::max();  ///< over all objects
  int64_t max_vertices = std::numeric_limits<int64_t>::max();   ///< over all objects
};

/// Which objects are alive, how each may move and how big it is, with the totals.
/// Thread safety: none (one owner).
class SceneModel {
 public:
  /// What the model keeps of one object.
  struct Object {
    Motion motion = Motion::kStatic;
    uint32_t num_vertices = 0;
    uint32_t num_triangles = 0;
  };

  /// Checks updates against the model as the batch's earlier updates leave it. Every check
  /// returns kInvalidArgument, kNotFound (id not alive) or kLimitExceeded (SceneLimits), with a
  /// message that starts with the field at fault, e.g. "id: object 4 is static; static objects
  /// take no poses", "rotation_wxyz: not a unit quaternion (norm 1.7)", so that the caller can
  /// put its own location in front ("frames[1].poses[0].", "record 7 (set_pose) ").
  /// A failed check changes nothing; the batch may go on or be dropped. Aliases the model: one
  /// batch at a time, and the model must outlive it.
  class Batch {
   public:
    Result<void> Add(uint32_t id, const Mesh& mesh, Motion motion, const Pose& X_WO);
    Result<void> Remove(uint32_t id);
    Result<void> SetPose(uint32_t id, const Pose& X_WO);
    Result<void> SetVertices(uint32_t id, std::span<const Eigen::Vector3d> p_MV);
    /// One of the above, by the update's kind.
    Result<void> Check(const SceneUpdate& update);

    /// The object as the batch leaves it; nullptr when not alive.
    const Object* Find(uint32_t id) const;
    /// Applies every update checked so far to the model, after reserving what the scene grows
    /// by from the model's shared budget. Errors: kLimitExceeded (the shared budget refused it,
    /// naming its rule: SharedSceneBudget; nothing changed).
    Result<void> Commit();

   private:
    friend class SceneModel;
    explicit Batch(SceneModel* model);
    std::optional<Object> Lookup(uint32_t id) const;

    SceneModel* model_;
    std::map<uint32_t, std::optional<Object>> changed_;  // nullopt: removed
    int64_t objects_, triangles_, vertices_;
  };

  /// A model within `limits`, drawing its totals from `shared` too when given (which must
  /// outlive it), as its holder `holder` (admitted there before the model grows).
  explicit SceneModel(SceneLimits limits = {}, SharedSceneBudget* shared = nullptr,
                      int64_t holder = 0)
      : limits_(limits), shared_(shared), holder_(holder) {}
  /// Gives its totals back to the shared budget.
  ~SceneModel();
  SceneModel(const SceneModel&) = delete;
  SceneModel& operator=(const SceneModel&) = delete;

  /// Starts a batch of updates.
  Batch Begin() { return Batch(this); }

  /// Checks `updates` in order as one batch and commits them when every one is valid. An error
  /// is prefixed with `where(i)` for the i-th update (default: "update <i> (<kind>) ").
  Result<void> Apply(std::span<const SceneUpdate> updates,
                     const std::function<std::string(size_t)>& where = {});

  /// The object with this id; nullptr when not alive.
  const Object* Find(uint32_t id) const;
  const std::map<uint32_t, Object>& objects() const { return objects_; }
  int64_t num_objects() const { return static_cast<int64_t>(objects_.size()); }
  int64_t num_triangles() const { return triangles_; }
  int64_t num_vertices() const { return vertices_; }
  const SceneLimits& limits() const { return limits_; }

 private:
  SceneLimits limits_;
  SharedSceneBudget* shared_ = nullptr;
  int64_t holder_ = 0;
  std::map<uint32_t, Object> objects_;
  int64_t triangles_ = 0;
  int64_t vertices_ = 0;
};

}  // namespace far
