#include "far/gpu/compute_batcher.h"

#include <algorithm>
#include <condition_variable>
#include <future>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "far/gpu/gl_context.h"
#include "far/gpu/gl_lock.h"

namespace far {

struct ComputeBatcher::Impl {
  // A step (query set) or a call to run on the thread (add, remove, a self-check).
  struct Job {
    ColliderId id = 0;
    const ComputeQuery* query = nullptr;
    std::promise<Result<ComputeAnswer>> answer;  // a step's
    std::function<void()> call;
  };

  mutable std::mutex mutex;
  std::condition_variable wake;
  std::vector<Job> jobs;  // guarded by mutex, like the three below
  bool stopping = false;
  bool held = false;
  Counters counters;
  std::string renderer;  // set once, before Create returns

  // The thread's own: the colliders by id, and the context they live in.
  std::unordered_map<ColliderId, std::unique_ptr<ComputeCollider>> colliders;
  ColliderId next_id = 0;
  std::thread thread;

  void Post(Job job) {
    {
      std::lock_guard lock(mutex);
      jobs.push_back(std::move(job));
    }
    wake.notify_one();
  }
  // Runs a call on the thread and waits for its value.
  template <typename T>
  T Call(std::function<T()> work) {
    // Shared: the thread may still be inside the task when the caller has its value.
    auto task = std::make_shared<std::packaged_task<T()>>(std::move(work));
    std::future<T> done = task->get_future();
    Job job;
    job.call = [task] { (*task)(); };
    Post(std::move(job));
    return done.get();
  }
  void Loop(GlPlatform platform, int device, std::promise<Result<void>> started);
  void RunBatch(std::vector<Job>& batch);
};

void ComputeBatcher::Impl::Loop(GlPlatform platform, int device,
                                std::promise<Result<void>> started) {
  auto context = GlContext::Create(platform, device);
  if (!context) {
    started.set_value(context.error());
    return;
  }
  renderer = (*context)->renderer();
  started.set_value({});
  for (;;) {
    std::vector<Job> batch;
    {
      std::unique_lock lock(mutex);
      wake.wait(lock, [&] { return !held && (stopping || !jobs.empty()); });
      if (jobs.empty()) break;  // stopping, and nothing left to do
      batch.swap(jobs);
    }
    RunBatch(batch);
  }
  const auto gl = LockGl();
  colliders.clear();  // their GL objects before the context
  context->reset();
}

// The calls first, in order (a session waits for its own add before it steps, and removes only
// between steps); then every step's GL work is issued, and then each answer is read back: the
// first read-back waits for the whole batch on the GPU, the others find their work done.
void ComputeBatcher::Impl::RunBatch(std::vector<Job>& batch) {
  const auto gl = LockGl();
  std::vector<Job*> steps;
  for (Job& job : batch) {
    if (job.query == nullptr) {
      job.call();
    } else {
      steps.push_back(&job);
    }
  }
  std::vector<ComputeCollider*> runners;
  std::vector<Result<void>> submitted;
  for (Job* step : steps) {
    auto found = colliders.find(step->id);
    runners.push_back(found == colliders.end() ? nullptr : found->second.get());
    submitted.push_back(
        runners.back() == nullptr
            ? Result<void>(MakeError(ErrorCode::kInternal,
                                     "gpu method: no collider " + std::to_string(step->id)))
            : runners.back()->Submit(*step->query));
  }
  if (!steps.empty()) {  // counted before any answer: a caller that has one sees its batch
    std::lock_guard lock(mutex);
    counters.steps += static_cast<int64_t>(steps.size());
    counters.batches += 1;
    counters.largest_batch = std::max(counters.largest_batch, static_cast<int64_t>(steps.size()));
  }
  for (size_t i = 0; i < steps.size(); ++i) {
    steps[i]->answer.set_value(submitted[i] ? runners[i]->Finish()
                                            : Result<ComputeAnswer>(submitted[i].error()));
  }
}

ComputeBatcher::ComputeBatcher(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Result<std::unique_ptr<ComputeBatcher>> ComputeBatcher::Create(GlPlatform platform, int device) {
  auto impl = std::make_unique<Impl>();
  std::promise<Result<void>> started;
  std::future<Result<void>> ready = started.get_future();
  Impl* raw = impl.get();
  impl->thread = std::thread([raw, platform, device, started = std::move(started)]() mutable {
    raw->Loop(platform, device, std::move(started));
  });
  Result<void> made = ready.get();
  if (!made) {
    impl->thread.join();
    return made.error();
  }
  return std::unique_ptr<ComputeBatcher>(new ComputeBatcher(std::move(impl)));
}

ComputeBatcher::~ComputeBatcher() {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stopping = true;
    impl_->held = false;
  }
  impl_->wake.notify_one();
  impl_->thread.join();
}

Result<ComputeBatcher::ColliderId> ComputeBatcher::AddCollider() {
  Impl& impl = *impl_;
  return impl.Call<Result<ColliderId>>([&impl]() -> Result<ColliderId> {
    auto made = ComputeCollider::Create();
    if (!made) return made.error();
    const ColliderId id = ++impl.next_id;
    impl.colliders.emplace(id, std::move(*made));
    return id;
  });
}

void ComputeBatcher::RemoveCollider(ColliderId id) {
  Impl::Job job;
  Impl& impl = *impl_;
  job.call = [&impl, id] { impl.colliders.erase(id); };
  impl.Post(std::move(job));
}

Result<ComputeAnswer> ComputeBatcher::Run(ColliderId id, const ComputeQuery& query) {
  Impl::Job job;
  job.id = id;
  job.query = &query;
  std::future<Result<ComputeAnswer>> answer = job.answer.get_future();
  impl_->Post(std::move(job));
  return answer.get();
}

Result<void> ComputeBatcher::WithCollider(ColliderId id,
                                          std::function<Result<void>(ComputeCollider&)> work) {
  Impl& impl = *impl_;
  return impl.Call<Result<void>>([&impl, id, &work]() -> Result<void> {
    auto found = impl.colliders.find(id);
    if (found == impl.colliders.end())
      return MakeError(ErrorCode::kInternal, "gpu method: no collider " + std::to_string(id));
    return work(*found->second);
  });
}

const std::string& ComputeBatcher::renderer() const {
  return impl_->renderer;  // set before Create returns, never again
}

ComputeBatcher::Counters ComputeBatcher::counters() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->counters;
}

void ComputeBatcher::HoldBatches(bool hold) {
  {
    std::lock_guard lock(impl_->mutex);
    impl_->held = hold;
  }
  impl_->wake.notify_one();
}

size_t ComputeBatcher::queued() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->jobs.size();
}

}  // namespace far
