#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "far/base/result.h"
#include "far/gpu/compute_collider.h"
#include "far/gpu/gl_platform.h"

namespace far {

/// One GL thread, with an OpenGL context of its own, that runs the gpu method's GPU work for
/// every pipeline of a process that hands it over (far-daemon's sessions). The thread issues
/// the steps waiting (each one's uploads and kernels, then its fence) as soon as it turns to
/// them, also while earlier steps are still on the GPU, and reads each step's answer back as
/// soon as its own fence has passed (ComputeCollider::Ready). Compared with every session
/// issuing its step on its own context in turns under the GL lock (ComputeCollider::Run), the
/// GPU gets one context's work back to back, without a switch between contexts, and works on
/// some steps while the thread issues and reads others.
///
/// Each session keeps its own collider (its buffers and hierarchies on the GPU), made, run and
/// destroyed on the batcher's thread. Thread-safe: any thread may call any method.
class ComputeBatcher {
 public:
  /// Starts the thread and makes its context there (GlContext::Create(platform, device)).
  /// Errors: the context's.
  static Result<std::unique_ptr<ComputeBatcher>> Create(GlPlatform platform = GlPlatform::kAuto,
                                                        int device = -1);
  /// Destroys the colliders still alive and the context, on the thread, and joins it.
  ~ComputeBatcher();
  ComputeBatcher(const ComputeBatcher&) = delete;
  ComputeBatcher& operator=(const ComputeBatcher&) = delete;

  using ColliderId = uint64_t;

  /// Makes a collider on the batcher's thread (ComputeCollider::Create); blocks until it is made.
  Result<ColliderId> AddCollider();
  /// Destroys collider `id` on the batcher's thread, after the steps already handed over; returns
  /// at once.
  void RemoveCollider(ColliderId id);
  /// Runs `query` on collider `id` (ComputeCollider::Submit when the thread turns to it, Finish
  /// once its GPU work is done); blocks until its answer is read back. The query's spans
  /// must live until it returns. Errors: ComputeCollider's; kInternal for an unknown id.
  Result<ComputeAnswer> Run(ColliderId id, const ComputeQuery& query);
  /// Runs `work` with collider `id` on the batcher's thread, outside any batch, and returns its
  /// result (a driver's self-check: far/pipeline's compute_self_check.h).
  Result<void> WithCollider(ColliderId id, std::function<Result<void>(ComputeCollider&)> work);

  /// GL_RENDERER of the batcher's context.
  const std::string& renderer() const;

  /// Steps run so far and the batches that carried them (a batch: the steps the thread issued
  /// in one turn).
  struct Counters {
    int64_t steps = 0;
    int64_t batches = 0;
    int64_t largest_batch = 0;
  };
  Counters counters() const;

  /// For tests: while held, steps queue up and no batch starts; `queued` says how many wait.
  void HoldBatches(bool hold);
  size_t queued() const;

 private:
  struct Impl;
  explicit ComputeBatcher(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace far
