#pragma once

// The fixture of every integration test: starts far-daemon processes and stops them in
// TearDown (SIGTERM; the exit code must be 0), printing their logs when the test failed.

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "daemon_process.h"
#include <gtest/gtest.h>

namespace far::integration {

class DaemonTest : public ::testing::Test {
 protected:
  /// Starts a daemon with `args` and waits until it answers; nullptr (and a test failure
  /// with the log) when it does not. Use: ASSERT_NE(StartDaemon(), nullptr).
  DaemonProcess* StartDaemon(std::vector<std::string> args = {}) {
    daemons_.push_back(std::make_unique<DaemonProcess>(std::move(args)));
    DaemonProcess& daemon = *daemons_.back();
    if (auto started = daemon.Start(); !started) {
      ADD_FAILURE() << far::ToString(started.error());
      return nullptr;
    }
    return &daemon;
  }

  /// Stops `daemon` with SIGTERM and expects exit code 0.
  void StopDaemon(DaemonProcess& daemon) {
    auto stopped = daemon.Stop();
    ASSERT_TRUE(stopped.ok()) << far::ToString(stopped.error()) << "\nlog:\n" << daemon.Log();
    EXPECT_EQ(*stopped, 0) << "far-daemon exit code; log:\n" << daemon.Log();
  }

  void TearDown() override {
    for (auto& daemon : daemons_) {
      if (daemon->Running()) StopDaemon(*daemon);
    }
    // FAR_INTEGRATION_LOGS=1 prints the logs of passing tests too.
    if (HasFailure() || std::getenv("FAR_INTEGRATION_LOGS") != nullptr) {
      for (size_t i = 0; i < daemons_.size(); ++i) {
        std::fprintf(stderr, "---- far-daemon %zu (pid %d) log %s ----\n%s---- end of log ----\n",
                     i, static_cast<int>(daemons_[i]->pid()), daemons_[i]->log_path().c_str(),
                     daemons_[i]->Log().c_str());
      }
    }
    daemons_.clear();  // SIGKILLs anything still running
  }

  std::vector<std::unique_ptr<DaemonProcess>> daemons_;
};

}  // namespace far::integration
