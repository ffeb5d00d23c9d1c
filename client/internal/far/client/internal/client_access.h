#pragma once

// What far-client's replay needs of a Client beyond its public interface. Never installed:
// only the far_client_internal target (tools/far-client) sees this folder.

#include "far/client/client.h"
#include "far/protocol/ring_records.h"

namespace far::client::internal {

/// Replay writes recorded ring records into a session's update ring bit for bit (the public
/// calls normalize poses, which may change the last bit of a recorded quaternion).
struct ClientAccess {
  /// The session's update ring; aliased, lives as long as `client`.
  static protocol::UpdateWriter& Updates(Client& client);
};

}  // namespace far::client::internal
