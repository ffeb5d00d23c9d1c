// The process's GL lock (far/gpu/gl_lock.h): fair, recursive, handed over by a holder that
// yields to the threads waiting then, and counting each thread's wait.
#include "far/gpu/gl_lock.h"

#include <atomic>
#include <chrono>
#include <mutex>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace far {
namespace {

using namespace std::chrono_literals;

// Waits (up to 5 s) until `done` says so.
template <typename F>
bool WaitUntil(F done) {
  const auto end = std::chrono::steady_clock::now() + 5s;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

TEST(GlLockTest, AYieldLetsTheWaitingThreadGoFirstAndCountsItsWait) {
  std::mutex mutex;
  std::vector<int> order;
  const auto note = [&](int who) {
    std::lock_guard lock(mutex);
    order.push_back(who);
  };
  GlLock held = LockGl();
  EXPECT_FALSE(held.contended());
  double waiter_waited_ms = 0;
  std::thread waiter([&] {
    const double before = GlLockWaitedMs();
    const GlLock gl = LockGl();
    waiter_waited_ms = GlLockWaitedMs() - before;
    note(2);
  });
  ASSERT_TRUE(WaitUntil([&] { return held.contended(); }));
  std::this_thread::sleep_for(50ms);
  const double yielded_ms = held.Yield();
  note(1);
  waiter.join();
  EXPECT_EQ(order, (std::vector<int>{2, 1})) << "the holder took the lock back first";
  EXPECT_GE(waiter_waited_ms, 40) << "the waiter's wait is counted on its thread";
  EXPECT_GE(yielded_ms, 0);
  EXPECT_FALSE(held.contended());
}

TEST(GlLockTest, AYieldReturnsAtOnceWhenNoneWaits) {
  GlLock held = LockGl();
  const double before = GlLockWaitedMs();
  EXPECT_EQ(held.Yield(), 0);
  EXPECT_EQ(GlLockWaitedMs(), before);
}

TEST(GlLockTest, AThreadThatHoldsItTwiceKeepsItThroughAYield) {
  std::atomic<bool> waiter_ran{false};
  std::thread waiter;
  {
    const GlLock outer = LockGl();
    GlLock inner = LockGl();  // recursive: no deadlock
    waiter = std::thread([&] {
      const GlLock gl = LockGl();
      waiter_ran = true;
    });
    ASSERT_TRUE(WaitUntil([&] { return inner.contended(); }));
    EXPECT_EQ(inner.Yield(), 0) << "an outer holder keeps the lock for its whole work";
    std::this_thread::sleep_for(20ms);
    EXPECT_FALSE(waiter_ran);
  }
  waiter.join();
  EXPECT_TRUE(waiter_ran);
}

TEST(GlLockTest, ThreadsThatWaitAreServedInTheOrderTheyCame) {
  std::mutex mutex;
  std::vector<int> order;
  std::vector<std::thread> waiters;
  {
    GlLock held = LockGl();
    for (int i = 0; i < 4; ++i) {
      waiters.emplace_back([&, i] {
        const GlLock gl = LockGl();
        std::lock_guard lock(mutex);
        order.push_back(i);
      });
      // The next one comes after this one waits.
      ASSERT_TRUE(WaitUntil([&] { return held.waiters() == i + 1; }));
    }
  }
  for (std::thread& waiter : waiters) waiter.join();
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3}));
}

}  // namespace
}  // namespace far
