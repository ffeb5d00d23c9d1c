#include "far/gpu/gl_lock.h"

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>

namespace far {
namespace {

// A recursive ticket lock: a thread takes a ticket and waits until it is served. Fair, so a
// holder that yields gets the lock back only after every thread that was waiting then.
class TicketLock {
 public:
  // Takes the lock (again, when this thread holds it); returns the ms waited.
  double Acquire() {
    std::unique_lock lock(mutex_);
    if (depth_ > 0 && owner_ == std::this_thread::get_id()) {
      ++depth_;
      return 0;
    }
    return Wait(lock, 1);
  }

  void Release() {
    std::lock_guard lock(mutex_);
    if (--depth_ > 0) return;
    Serve();
  }

  // Tickets taken and not yet served, but the holder's.
  int waiters() const {
    std::lock_guard lock(mutex_);
    return static_cast<int>(next_ticket_ - serving_) - (depth_ > 0 ? 1 : 0);
  }

  // Hands the lock to the threads waiting now and takes it back after them; ms waited.
  double Yield() {
    std::unique_lock lock(mutex_);
    if (depth_ != 1 || next_ticket_ - serving_ <= 1) return 0;
    Serve();
    return Wait(lock, 1);
  }

 private:
  // Takes a ticket and waits for it (mutex_ held); then this thread holds the lock `depth` deep.
  double Wait(std::unique_lock<std::mutex>& lock, int depth) {
    const auto start = std::chrono::steady_clock::now();
    const uint64_t ticket = next_ticket_++;
    served_.wait(lock, [&] { return serving_ == ticket; });
    owner_ = std::this_thread::get_id();
    depth_ = depth;
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
        .count();
  }
  // Ends the holder's turn (mutex_ held).
  void Serve() {
    owner_ = {};
    depth_ = 0;
    ++serving_;
    served_.notify_all();
  }

  mutable std::mutex mutex_;
  std::condition_variable served_;
  uint64_t next_ticket_ = 0, serving_ = 0;
  std::thread::id owner_;
  int depth_ = 0;
};

TicketLock& TheLock() {
  static TicketLock lock;
  return lock;
}

thread_local double waited_ms = 0;

}  // namespace

GlLock LockGl() { return GlLock(); }

double GlLockWaitedMs() { return waited_ms; }

GlLock::GlLock() { waited_ms += TheLock().Acquire(); }
GlLock::~GlLock() { TheLock().Release(); }

int GlLock::waiters() const { return TheLock().waiters(); }

double GlLock::Yield() {
  const double ms = TheLock().Yield();
  waited_ms += ms;
  return ms;
}

}  // namespace far
