#include "step_cpu_meter.h"

#include <pthread.h>

#include <gtest/gtest.h>

namespace far::server {
namespace {

// This thread's CPU clock (Linux always has one).
std::optional<clockid_t> OwnClock() {
  clockid_t clock;
  EXPECT_EQ(pthread_getcpuclockid(pthread_self(), &clock), 0);
  return clock;
}

// Spends `ms` of this thread's CPU time.
void Burn(std::optional<clockid_t> clock, double ms) {
  const double until = ThreadCpuMs(clock) + ms;
  volatile double sink = 0;
  while (ThreadCpuMs(clock) < until) sink = sink + 1;
}

TEST(StepCpuMeterTest, CoveredSetupDoesNotCountAndTheRestDoes) {
  const auto clock = OwnClock();
  SetupAllowance allowance(1000);
  StepCpuMeter meter(clock, allowance, 1000);
  meter.BeginSetup();
  meter.BeginSetup();  // nested: one part
  Burn(clock, 30);
  EXPECT_LT(meter.SteadyMs(), 10) << "a part still running counts as covered";
  meter.EndSetup();
  Burn(clock, 5);
  meter.EndSetup();
  // The user's allowance paid for the setup (its bucket was made full at that take).
  EXPECT_LE(allowance.Available(1000), 1000 - 35 + 1);
  EXPECT_GE(meter.setup_ms(), 35);
  EXPECT_DOUBLE_EQ(meter.covered_ms(), meter.setup_ms());
  EXPECT_LT(meter.SteadyMs(), 10);
  Burn(clock, 20);
  EXPECT_GE(meter.SteadyMs(), 20);
  EXPECT_LT(meter.SteadyMs(), 35);
  meter.EndSetup();  // an end without a begin changes nothing
  EXPECT_GE(meter.SteadyMs(), 20);
}

TEST(StepCpuMeterTest, SetupPastTheAllowanceCounts) {
  const auto clock = OwnClock();
  SetupAllowance allowance(10);
  StepCpuMeter meter(clock, allowance, 1000);
  meter.BeginSetup();
  Burn(clock, 40);
  meter.EndSetup();
  EXPECT_GE(meter.setup_ms(), 40);
  EXPECT_LE(meter.covered_ms(), 11);  // the burst, and what came back meanwhile
  EXPECT_GE(meter.SteadyMs(), 29);
}

}  // namespace
}  // namespace far::server
