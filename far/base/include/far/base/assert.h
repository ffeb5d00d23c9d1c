#pragma once

// Checks of far's own invariants, in two tiers (Drake's DRAKE_ASSERT / DRAKE_DEMAND, iceoryx's
// IOX_ENFORCE):
//   FAR_ASSERT(condition, message)  debug builds only (compiled out under NDEBUG): our own bugs
//                                   that cannot corrupt memory, checked where they are cheap.
//   FAR_DEMAND(condition, message)  always on: invariants whose failure would read or write out
//                                   of bounds, in every build.
// Never either on client data: untrusted input is validated and answered with a far::Error
// (far/base/result.h). A failed check prints the condition, the message and where, then aborts.

#include <string_view>

namespace far::internal {

/// What a failed check reports.
struct AssertionFailure {
  const char* condition;
  std::string_view message;
  const char* file;
  int line;
};

/// Reports a failed check through the handler (default: one line on stderr), then aborts.
[[noreturn]] void AssertionFailed(const AssertionFailure& failure);

/// Replaces the handler AssertionFailed calls before it aborts (nullptr: the default). A handler
/// that throws leaves by the exception instead: how tests check that a check fires. Not
/// thread-safe: set it before the threads that may fail start. Returns the previous handler.
using AssertionHandler = void (*)(const AssertionFailure&);
AssertionHandler SetAssertionHandler(AssertionHandler handler);

}  // namespace far::internal

#define FAR_DEMAND(condition, message)                                               \
  do {                                                                               \
    if (!(condition)) [[unlikely]]                                                   \
      ::far::internal::AssertionFailed({#condition, (message), __FILE__, __LINE__}); \
  } while (false)

#ifdef NDEBUG
// Compiled out, but still type-checked (never evaluated).
#define FAR_ASSERT(condition, message)          \
  do {                                          \
    (void)sizeof(static_cast<bool>(condition)); \
    (void)sizeof(std::string_view(message));    \
  } while (false)
#else
#define FAR_ASSERT(condition, message) FAR_DEMAND(condition, message)
#endif
