#pragma once

// A client that runs as another user: user_limits_test.cc starts this binary as
// `far_integration_test --far-other-user <socket>` with its uid switched (ChildProcess::Spawn
// with a user), so that the daemon sees a second user on its socket (SO_PEERCRED).

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

}  // namespace far::integration
