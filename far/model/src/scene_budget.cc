#include "far/model/scene_budget.h"

#include <string>

namespace far {

Result<void> SharedSceneBudget::Reserve(int64_t vertices, int64_t triangles) {
  std::lock_guard lock(mutex_);
  if (vertices > max_vertices_ - vertices_) {
    return MakeError(ErrorCode::kLimitExceeded,
                     "memory budget: " + std::to_string(vertices) + " more vertices would make " +
                         std::to_string(vertices_ + vertices) + " in all sessions, over the " +
                         std::to_string(max_vertices_) + " this daemon allows");
  }
  if (triangles > max_triangles_ - triangles_) {
    return MakeError(ErrorCode::kLimitExceeded,
                     "memory budget: " + std::to_string(triangles) + " more triangles would make " +
                         std::to_string(triangles_ + triangles) + " in all sessions, over the " +
                         std::to_string(max_triangles_) + " this daemon allows");
  }
  vertices_ += vertices;
  triangles_ += triangles;
  return {};
}

void SharedSceneBudget::Release(int64_t vertices, int64_t triangles) {
  std::lock_guard lock(mutex_);
  vertices_ -= vertices;
  triangles_ -= triangles;
}

int64_t SharedSceneBudget::vertices() const {
  std::lock_guard lock(mutex_);
  return vertices_;
}

int64_t SharedSceneBudget::triangles() const {
  std::lock_guard lock(mutex_);
  return triangles_;
}

}  // namespace far
