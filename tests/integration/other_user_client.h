#pragma once

// A client that runs as another user: user_limits_test.cc starts this binary as
// `far_integration_test --far-other-user <socket>` with its uid switched (ChildProcess::Spawn
// with a user), so that the daemon sees a second user on its socket (SO_PEERCRED).

#include <sys/types.h>

#include <cstdint>
#include <string>

namespace far::integration {

/// Opens a session named kOtherUserClientName on `socket`, uploads ContactSoup(kHealthySeed),
/// steps once and asks for the daemon's status. Prints, one per line:
///   stepped <uid> <contacts>
///   session <uid> <client name> <triangles>     (one per session the status lists)
///   end <sessions_open>
/// then keeps its session open until it is killed (at most 60 s). On a failure it prints
/// "error <message>" and exits 2.
int OtherUserClientMain(const std::string& socket);

inline constexpr const char* kOtherUserClientName = "other-user";

/// The other user's uid in the tests that need a second user (Debian's nobody).
inline constexpr uid_t kOtherUid = 65534;

/// A user that holds sessions (fair_shares_test.cc starts this binary as
/// `far_integration_test --far-hold <socket> <sessions> <triangles> <go file>` as another uid):
/// opens `sessions` sessions named "holder-<i>" on `socket`, each with one static object of
/// `triangles` degenerate triangles (one vertex, every triangle (0, 0, 0); 0: no object),
/// stepped once so that the daemon holds them, and prints
///   held <sessions opened> <triangles held>
/// (or "error <message>" and exits 2). It then leaves them idle until the file `go` exists
/// (at most 60 s), steps each once more and prints, one per session, then "end":
///   session <i> ok
///   session <i> error <code>: <message>
int HoldingClientMain(const std::string& socket, int sessions, int64_t triangles,
                      const std::string& go);

}  // namespace far::integration
