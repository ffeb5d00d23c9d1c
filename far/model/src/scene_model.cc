#include "far/model/scene_model.h"

#include <algorithm>
#include <string>

#include "far/base/limits.h"

namespace far {
namespace {

std::string ObjectName(uint32_t id) { return "object " + std::to_string(id); }

Error NotAlive(uint32_t id) {
  return MakeError(ErrorCode::kNotFound, "id: " + ObjectName(id) + " is not in the scene");
}

// A content error with the field it names moved under `parent` ("mesh", "pose").
Error Under(const std::string& parent, const Error& error) {
  return MakeError(error.code, parent + "." + error.message);
}

// Every coordinate finite and within +-kMaxCoordinate; the error names the first that is not.
Result<void> CheckPositions(std::span<const Eigen::Vector3d> p_MV) {
  // Branch-free, so that it vectorizes (a deformable object sends every vertex every step):
  // |x| <= max is false for NaN and infinities too. Only when some value fails, find it.
  bool all_fine = true;
  for (const Eigen::Vector3d& p : p_MV) all_fine &= p.cwiseAbs().maxCoeff() <= kMaxCoordinate;
  if (all_fine) return {};
  for (size_t v = 0; v < p_MV.size(); ++v) {
    if (!p_MV[v].allFinite()) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "vertex " + std::to_string(v) + " is not finite");
    }
    if (p_MV[v].cwiseAbs().maxCoeff() > kMaxCoordinate) {
      return MakeError(ErrorCode::kInvalidArgument,
                       "vertex " + std::to_string(v) + " has a coordinate beyond +-" +
                           FormatDouble(kMaxCoordinate) + " (" +
                           FormatDouble(p_MV[v].cwiseAbs().maxCoeff()) + ")");
    }
  }
  return {};
}

// CheckPose, and the translation within +-kMaxCoordinate.
Result<void> CheckPoseInRange(const Pose& X_WO) {
  if (auto valid = CheckPose(X_WO); !valid) return valid;
  if (X_WO.translation.cwiseAbs().maxCoeff() > kMaxCoordinate) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "translation: a coordinate beyond +-" + FormatDouble(kMaxCoordinate) + " (" +
                         FormatDouble(X_WO.translation.cwiseAbs().maxCoeff()) + ")");
  }
  return {};
}

}  // namespace

SceneModel::Batch::Batch(SceneModel* model)
    : model_(model),
      objects_(model->num_objects()),
      triangles_(model->triangles_),
      vertices_(model->vertices_) {}

std::optional<SceneModel::Object> SceneModel::Batch::Lookup(uint32_t id) const {
  if (auto it = changed_.find(id); it != changed_.end()) return it->second;
  if (const Object* object = model_->Find(id)) return *object;
  return std::nullopt;
}

const SceneModel::Object* SceneModel::Batch::Find(uint32_t id) const {
  if (auto it = changed_.find(id); it != changed_.end()) return it->second ? &*it->second : nullptr;
  return model_->Find(id);
}

Result<void> SceneModel::Batch::Add(uint32_t id, const Mesh& mesh, Motion motion,
                                    const Pose& X_WO) {
  if (Lookup(id))
    return MakeError(ErrorCode::kInvalidArgument,
                     "id: " + ObjectName(id) + " is already in the scene");
  if (auto valid = ValidateMesh(mesh); !valid) {
    return MakeError(valid.error().code, "mesh: " + valid.error().message);
  }
  if (auto valid = CheckPositions(mesh.p_MV); !valid) {
    return MakeError(valid.error().code, "mesh: " + valid.error().message);
  }
  if (auto valid = CheckPoseInRange(X_WO); !valid) return Under("pose", valid.error());
  // Budgets: counted as if every update of the batch so far were applied.
  const SceneLimits& limits = model_->limits_;
  if (objects_ + 1 > limits.max_objects) {
    return MakeError(
        ErrorCode::kLimitExceeded,
        "id: the scene would have more than " + std::to_string(limits.max_objects) + " objects");
  }
  if (triangles_ + mesh.num_triangles() > limits.max_triangles) {
    return MakeError(ErrorCode::kLimitExceeded,
                     "mesh: the scene would have " +
                         std::to_string(triangles_ + mesh.num_triangles()) + " triangles (limit " +
                         std::to_string(limits.max_triangles) + ")");
  }
  if (vertices_ + mesh.num_vertices() > limits.max_vertices) {
    return MakeError(ErrorCode::kLimitExceeded,
                     "mesh: the scene would have " +
                         std::to_string(vertices_ + mesh.num_vertices()) + " vertices (limit " +
                         std::to_string(limits.max_vertices) + ")");
  }
  objects_ += 1;
  triangles_ += mesh.num_triangles();
  vertices_ += mesh.num_vertices();
  changed_[id] = Object{motion, static_cast<uint32_t>(mesh.num_vertices()),
                        static_cast<uint32_t>(mesh.num_triangles())};
  return {};
}

Result<void> SceneModel::Batch::Remove(uint32_t id) {
  const std::optional<Object> object = Lookup(id);
  if (!object) return NotAlive(id);
  objects_ -= 1;
  triangles_ -= object->num_triangles;
  vertices_ -= object->num_vertices;
  changed_[id] = std::nullopt;
  return {};
}

Result<void> SceneModel::Batch::SetPose(uint32_t id, const Pose& X_WO) {
  const std::optional<Object> object = Lookup(id);
  if (!object) return NotAlive(id);
  if (object->motion == Motion::kStatic) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "id: " + ObjectName(id) + " is static; static objects take no poses");
  }
  return CheckPoseInRange(X_WO);
}

Result<void> SceneModel::Batch::SetVertices(uint32_t id, std::span<const Eigen::Vector3d> p_MV) {
  const std::optional<Object> object = Lookup(id);
  if (!object) return NotAlive(id);
  if (object->motion != Motion::kDeformable) {
    return MakeError(ErrorCode::kInvalidArgument, "id: " + ObjectName(id) + " is " +
                                                      ToString(object->motion) +
                                                      "; only deformable objects take vertices");
  }
  if (p_MV.size() != object->num_vertices) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "mesh: " + std::to_string(p_MV.size()) + " vertices given, " + ObjectName(id) +
                         " has " + std::to_string(object->num_vertices));
  }
  if (auto valid = CheckPositions(p_MV); !valid) {
    return MakeError(valid.error().code, "mesh: " + valid.error().message);
  }
  return {};
}

Result<void> SceneModel::Batch::Check(const SceneUpdate& update) {
  return std::visit(
      [this](const auto& u) -> Result<void> {
        using T = std::decay_t<decltype(u)>;
        if constexpr (std::is_same_v<T, AddObject>) {
          return Add(u.id, u.mesh, u.motion, u.X_WO);
        } else if constexpr (std::is_same_v<T, RemoveObject>) {
          return Remove(u.id);
        } else if constexpr (std::is_same_v<T, far::SetPose>) {
          return SetPose(u.id, u.X_WO);
        } else {
          return SetVertices(u.id, u.p_MV);
        }
      },
      update);
}

Result<void> SceneModel::Batch::Commit() {
  // The shared budget first: growth is reserved before anything changes, shrinkage returned
  // after.
  const int64_t grow_vertices = vertices_ - model_->vertices_;
  const int64_t grow_triangles = triangles_ - model_->triangles_;
  if (model_->shared_ != nullptr && (grow_vertices > 0 || grow_triangles > 0)) {
    const auto more = BudgetAmounts::Scene(std::max<int64_t>(grow_vertices, 0),
                                           std::max<int64_t>(grow_triangles, 0));
    if (auto ok = model_->shared_->Reserve(model_->holder_, more); !ok) return ok;
  }
  if (model_->shared_ != nullptr && (grow_vertices < 0 || grow_triangles < 0)) {
    model_->shared_->Release(model_->holder_,
                             BudgetAmounts::Scene(std::max<int64_t>(-grow_vertices, 0),
                                                  std::max<int64_t>(-grow_triangles, 0)));
  }
  for (const auto& [id, object] : changed_) {
    if (object) {
      model_->objects_[id] = *object;
    } else {
      model_->objects_.erase(id);
    }
  }
  model_->triangles_ = triangles_;
  model_->vertices_ = vertices_;
  changed_.clear();
  return {};
}

SceneModel::~SceneModel() {
  if (shared_ != nullptr) shared_->Release(holder_, BudgetAmounts::Scene(vertices_, triangles_));
}

Result<void> SceneModel::Apply(std::span<const SceneUpdate> updates,
                               const std::function<std::string(size_t)>& where) {
  Batch batch = Begin();
  for (size_t i = 0; i < updates.size(); ++i) {
    if (auto ok = batch.Check(updates[i]); !ok) {
      const std::string place =
          where ? where(i) : "update " + std::to_string(i) + " (" + UpdateName(updates[i]) + ") ";
      return MakeError(ok.error().code, place + ok.error().message);
    }
  }
  return batch.Commit();
}

const SceneModel::Object* SceneModel::Find(uint32_t id) const {
  auto it = objects_.find(id);
  return it == objects_.end() ? nullptr : &it->second;
}

}  // namespace far
