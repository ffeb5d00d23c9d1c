#pragma once
// far-client load --client-cpu-ms: a load client spends CPU time of its own before each step,
// as a simulator's physics step would, so that the daemon is measured on cores it shares.

namespace far::cli {

/// The most --client-cpu-ms may ask for: 10 s of CPU per step.
inline constexpr double kMaxClientCpuMs = 10'000;

/// Spins on arithmetic until the calling thread has used `ms` of its own CPU time
/// (CLOCK_THREAD_CPUTIME_ID: time spent waiting for a core does not count, so on busy cores the
/// wall time is longer; a sleep would cost no CPU at all). Returns the CPU ms used, at least
/// `ms`; 0 when `ms` <= 0 or the clock cannot be read. Thread-safe.
double BurnThreadCpuMs(double ms);

}  // namespace far::cli
