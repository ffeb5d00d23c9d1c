#pragma once

// Session slots: one user opening sessions as fast as it can, and a second user (uid 65534,
// when this program runs as root) trying a few opens while the first holds all it got.

#include <memory>
#include <string>
#include <vector>

#include "study_daemon.h"

#include "far/client/client.h"

namespace far::study {

struct OpenReport {
  int attempts = 0, opened = 0, refused = 0;
  double seconds = 0;   ///< for all the attempts
  std::string refusal;  ///< the first refusal's message
  std::string not_run;  ///< why the attempts were not made ("" when they were)
};

/// Opens sessions back to back, `attempts` times, keeping those it gets in `held`.
OpenReport OpenAsFastAsPossible(const StudyDaemon& daemon, int attempts,
                                std::vector<std::unique_ptr<client::Client>>* held);

/// Runs `self` (this program) as uid 65534 with kOtherUserFlag to make `attempts` opens on
/// `socket`, keeping them open until all are made. Not run (not_run says why) unless root.
OpenReport OpenAsOtherUser(const std::string& self, const std::string& socket, int attempts);

/// The flag of the child mode, and the child's main: prints "opened <k> refused <m> <seconds>"
/// and then the first refusal's message on a line of its own.
inline constexpr const char* kOtherUserFlag = "--open-as-other-user";
int OtherUserMain(const std::string& socket, int attempts);

}  // namespace far::study
