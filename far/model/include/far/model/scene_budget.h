#pragma once

// A memory budget several scenes share: a daemon's sessions draw their vertices and triangles
// from one daemon-wide total, so that no set of clients can make it allocate without bound
// even when each stays within its own session limits.

#include <cstdint>
#include <mutex>

#include "far/base/result.h"

namespace far {

/// Totals reserved by scene models (SceneModel with this budget) as they grow and released as
/// they shrink or are destroyed. Thread-safe.
class SharedSceneBudget {
 public:
  SharedSceneBudget(int64_t max_vertices, int64_t max_triangles)
      : max_vertices_(max_vertices), max_triangles_(max_triangles) {}

  /// Adds the amounts (>= 0) when both totals stay within the budget; otherwise changes nothing.
  /// Errors: kLimitExceeded naming the total and the budget.
  Result<void> Reserve(int64_t vertices, int64_t triangles);
  /// Gives back amounts (>= 0) reserved before.
  void Release(int64_t vertices, int64_t triangles);

  int64_t vertices() const;
  int64_t triangles() const;
  int64_t max_vertices() const { return max_vertices_; }
  int64_t max_triangles() const { return max_triangles_; }

 private:
  const int64_t max_vertices_, max_triangles_;
  mutable std::mutex mutex_;
  int64_t vertices_ = 0, triangles_ = 0;
};

}  // namespace far
