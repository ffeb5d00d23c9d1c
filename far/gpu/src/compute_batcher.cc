#include "far/gpu/compute_batcher.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <future>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <utility>
#include <vector>

#include "far/base/timer_slack.h"
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
  // A step whose GPU work is issued, in the order issued (the GPU's order too).
  struct InFlight {
    Job job;
    ComputeCollider* collider;
  };
  void Loop(GlPlatform platform, int device, std::promise<Result<void>> started);
  // Runs the calls taken, then submits the steps taken (answering at once those that fail).
  void Start(std::vector<Job>& taken, std::deque<InFlight>& in_flight);
};

// While steps are on the GPU the thread looks for new ones and for finished ones this often.
constexpr auto kPoll = std::chrono::microseconds(20);

// Submits the steps waiting as soon as they come, and reads each answer back as soon as its own
// GPU work is done: the GPU works on the steps in flight while the thread issues the next ones
// and reads the answers of the finished ones. (Submitting a batch, then waiting for all of it,
// left the GPU idle while the thread issued and read: on the H200 16 clients got batches of 2.3
// steps on average, one after another.)
void ComputeBatcher::Impl::Loop(GlPlatform platform, int device,
                                std::promise<Result<void>> started) {
  auto context = GlContext::Create(platform, device);
  if (!context) {
    started.set_value(context.error());
    return;
  }
  renderer = (*context)->renderer();
  started.set_value({});
  const ScopedTimerSlack slack(1000);  // the polls' short waits: 20 us, not 70 (WaitAndDelete)
  std::deque<InFlight> in_flight;
  for (;;) {
    std::vector<Job> taken;
    {
      std::unique_lock lock(mutex);
      const auto ready = [&] {
        return (!held && !jobs.empty()) || (stopping && in_flight.empty());
      };
      if (in_flight.empty()) {
        wake.wait(lock, ready);
      } else {
        wake.wait_for(lock, kPoll, ready);
      }
      if (!held) taken.swap(jobs);
      if (stopping && taken.empty() && in_flight.empty()) break;
    }
    const auto gl = LockGl();
    Start(taken, in_flight);
    while (!in_flight.empty() && in_flight.front().collider->Ready()) {
      InFlight& done = in_flight.front();
      done.job.answer.set_value(done.collider->Finish());
      in_flight.pop_front();
    }
  }
  const auto gl = LockGl();
  colliders.clear();  // their GL objects before the context
  context->reset();
}

// The calls first, in order (a session waits for its own add before it steps, and removes only
// between steps, so no call touches a collider whose step is in flight); then the steps.
void ComputeBatcher::Impl::Start(std::vector<Job>& taken, std::deque<InFlight>& in_flight) {
  const int64_t steps =
      std::count_if(taken.begin(), taken.end(), [](const Job& job) { return job.query; });
  if (steps > 0) {  // counted before any answer: a caller that has one sees its batch
    std::lock_guard lock(mutex);
    counters.steps += steps;
    counters.batches += 1;
    counters.largest_batch = std::max(counters.largest_batch, steps);
  }
  for (Job& job : taken) {
    if (job.query == nullptr) job.call();
  }
  for (Job& job : taken) {
    if (job.query == nullptr) continue;
    auto found = colliders.find(job.id);
    if (found == colliders.end()) {
      job.answer.set_value(
          MakeError(ErrorCode::kInternal, "gpu method: no collider " + std::to_string(job.id)));
      continue;
    }
    if (auto ok = found->second->Submit(*job.query); !ok) {
      job.answer.set_value(ok.error());
      continue;
    }
    in_flight.push_back({std::move(job), found->second.get()});
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
