#pragma once

// How late a thread's sleeps may wake, for a wait that polls in short sleeps.

namespace far {

/// Lowers the calling thread's timer slack to `slack_ns` while it lives, then restores it.
/// Linux lets a sleep wake up to the thread's timer slack late (50 us by default) so that
/// wake-ups can be batched: a poll that sleeps 20 us between looks then takes about 100 us a
/// look (109 us median on the 2-core CI machine, 46 us with 1 us of slack), and the gpu step
/// waits on its fence that way. Elsewhere than on Linux it does nothing.
class ScopedTimerSlack {
 public:
  explicit ScopedTimerSlack(unsigned long slack_ns);
  ~ScopedTimerSlack();
  ScopedTimerSlack(const ScopedTimerSlack&) = delete;
  ScopedTimerSlack& operator=(const ScopedTimerSlack&) = delete;

  /// The calling thread's timer slack now, in nanoseconds (0 where it cannot be read).
  static unsigned long Current();

 private:
  unsigned long saved_ns_ = 0;  // 0: nothing to restore
};

}  // namespace far
