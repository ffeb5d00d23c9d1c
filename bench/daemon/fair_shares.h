#pragma once

// Fair shares of the daemon-wide budgets (issue 41): sessions held by other users (uids that
// this program switches to in a child process, when it runs as root), so that the study can see
// what a user finds when others hold all they can:
//   - one uid with 4 sessions of 2M degenerate triangles (one vertex, every triangle (0,0,0):
//     nothing to build), idle once uploaded, against the 8M-triangle budget;
//   - four uids with 16 empty sessions each, against the 64 session slots.
// The child opens its sessions, says what it got on its stdout, keeps them (idle) until its
// stdin closes, then tries one step on each and says how many still worked.

#include <sys/types.h>

#include <cstdint>
#include <memory>
#include <string>

namespace far::study {

/// What a child holding sessions reported.
struct HeldReport {
  int opened = 0, refused = 0;  ///< sessions
  int64_t triangles = 0;        ///< uploaded and applied (stepped once), all sessions
  double seconds = 0;           ///< to open and upload them all
  std::string refusal;          ///< the first refusal or failure ("" when none)
  int alive_after = -1;         ///< sessions whose step worked when the child was let go
  std::string closed_because;   ///< the first step failure then ("" when none)
  std::string not_run;          ///< why there is no child ("" when it ran)
};

/// A child process of this program that runs as `uid` and holds sessions on a daemon.
class HeldSessions {
 public:
  /// Starts `self` as `uid` with kHoldAsUserFlag: `sessions` sessions on `socket`, each with one
  /// object of `triangles` degenerate triangles (0: none), and waits for its report. When this
  /// program is not root, or the child cannot switch, report().not_run says why.
  static std::unique_ptr<HeldSessions> Start(const std::string& self, const std::string& socket,
                                             uid_t uid, int sessions, int64_t triangles);
  ~HeldSessions();
  HeldSessions(const HeldSessions&) = delete;
  HeldSessions& operator=(const HeldSessions&) = delete;

  /// Lets the child go: it steps each session once, reports how many worked, and ends.
  void Finish();
  const HeldReport& report() const { return report_; }
  uid_t uid() const { return uid_; }

 private:
  HeldSessions() = default;
  HeldReport report_;
  uid_t uid_ = 0;
  pid_t pid_ = -1;
  int to_child_ = -1, from_child_ = -1;
};

/// The flag of the child mode, and the child's main (socket, sessions, triangles per session).
inline constexpr const char* kHoldAsUserFlag = "--hold-as-user";
int HoldAsUserMain(const std::string& socket, int sessions, int64_t triangles);

/// "8.0M" for a triangle count of 8,000,000 ("960" below 10,000).
std::string Millions(int64_t count);

}  // namespace far::study
