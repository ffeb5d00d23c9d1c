#include "shm_access.h"

#include <sys/mman.h>

#include <mutex>

namespace far::protocol::internal {
namespace {

// The range this thread is accessing. initial-exec TLS: safe to read in a signal handler.
__attribute__((tls_model("initial-exec"))) thread_local MappedRange* tls_range = nullptr;

struct sigaction g_previous_action;

void OnSigbus(int signal, siginfo_t* info, void* context) {
  MappedRange* range = tls_range;
  const auto* address = static_cast<const uint8_t*>(info->si_addr);
  if (range != nullptr && address >= range->base && address < range->base + range->size) {
    // Replace the segment with zero pages; the faulting instruction then succeeds.
    void* remapped = mmap(range->base, range->size, PROT_READ | PROT_WRITE,
                          MAP_PRIVATE | MAP_ANONYMOUS | MAP_FIXED, -1, 0);
    if (remapped != MAP_FAILED) {
      range->faulted = 1;
      return;
    }
  }
  // Not ours (or the remap failed): behave as if we had never been installed.
  if ((g_previous_action.sa_flags & SA_SIGINFO) != 0 && g_previous_action.sa_sigaction != nullptr) {
    g_previous_action.sa_sigaction(signal, info, context);
    return;
  }
  if (g_previous_action.sa_handler != SIG_DFL && g_previous_action.sa_handler != SIG_IGN) {
    g_previous_action.sa_handler(signal);
    return;
  }
  // Default action: restore it and return; the faulting instruction runs again and the
  // process dies of SIGBUS as it would have without us.
  sigaction(SIGBUS, &g_previous_action, nullptr);
}

void InstallHandler() {
  static std::once_flag once;
  std::call_once(once, [] {
    struct sigaction action {};
    action.sa_sigaction = &OnSigbus;
    action.sa_flags = SA_SIGINFO;
    sigemptyset(&action.sa_mask);
    sigaction(SIGBUS, &action, &g_previous_action);
  });
}

}  // namespace

ScopedShmAccess::ScopedShmAccess(MappedRange* range) : range_(range), previous_(tls_range) {
  if (range_ != nullptr) {
    InstallHandler();
    tls_range = range_;
  }
}

ScopedShmAccess::~ScopedShmAccess() {
  if (range_ != nullptr) tls_range = previous_;
}

}  // namespace far::protocol::internal
