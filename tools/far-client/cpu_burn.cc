#include "cpu_burn.h"

#include <time.h>

#include <cstdint>

namespace far::cli {
namespace {

// The calling thread's CPU time, ms, or -1 when the clock cannot be read.
double ThreadCpuMs() {
  timespec now{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now) != 0) return -1;
  return static_cast<double>(now.tv_sec) * 1e3 + static_cast<double>(now.tv_nsec) * 1e-6;
}

}  // namespace

double BurnThreadCpuMs(double ms) {
  const double start = ThreadCpuMs();
  if (!(ms > 0) || start < 0) return 0;
  double now = start;
  uint64_t x = 0x9E3779B97F4A7C15ull;
  while (now - start < ms) {
    // A few microseconds of arithmetic between two reads of the clock (a system call). The
    // empty asm says x is used at every iteration, so the compiler can neither drop the loop
    // nor fold it into a closed form.
    for (int i = 0; i < 4096; ++i) {
      x = x * 6364136223846793005ull + 1442695040888963407ull;
      asm volatile("" : "+r"(x));
    }
    now = ThreadCpuMs();
  }
  return now - start;
}

}  // namespace far::cli
