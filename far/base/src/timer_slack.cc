#include "far/base/timer_slack.h"

#if defined(__linux__)
#include <sys/prctl.h>
#endif

namespace far {

ScopedTimerSlack::ScopedTimerSlack(unsigned long slack_ns) {
  saved_ns_ = Current();
#if defined(__linux__)
  if (saved_ns_ != 0) prctl(PR_SET_TIMERSLACK, slack_ns, 0, 0, 0);
#else
  (void)slack_ns;
#endif
}

ScopedTimerSlack::~ScopedTimerSlack() {
#if defined(__linux__)
  // 0 would not restore: PR_SET_TIMERSLACK 0 means "the process's default slack".
  if (saved_ns_ != 0) prctl(PR_SET_TIMERSLACK, saved_ns_, 0, 0, 0);
#endif
}

unsigned long ScopedTimerSlack::Current() {
#if defined(__linux__)
  const int slack = prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0);
  return slack > 0 ? static_cast<unsigned long>(slack) : 0;
#else
  return 0;
#endif
}

}  // namespace far
