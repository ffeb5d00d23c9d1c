#include "far/base/assert.h"

#include <cstdio>
#include <cstdlib>

namespace far::internal {
namespace {

AssertionHandler g_handler = nullptr;

void PrintFailure(const AssertionFailure& failure) {
  std::fprintf(stderr, "far: internal check failed: %s (%.*s) at %s:%d\n", failure.condition,
               static_cast<int>(failure.message.size()), failure.message.data(), failure.file,
               failure.line);
  std::fflush(stderr);
}

}  // namespace

void AssertionFailed(const AssertionFailure& failure) {
  if (g_handler != nullptr) {
    g_handler(failure);
  } else {
    PrintFailure(failure);
  }
  std::abort();
}

AssertionHandler SetAssertionHandler(AssertionHandler handler) {
  const AssertionHandler previous = g_handler;
  g_handler = handler;
  return previous;
}

}  // namespace far::internal
