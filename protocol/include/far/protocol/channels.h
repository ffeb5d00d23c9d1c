#pragma once

// Where a daemon is reached. Each daemon has a name (default "far"); the name picks its local
// socket and the prefix of its LCM channels, so several daemons can serve one machine (one per
// GPU, say) and a client chooses one by name.
//   <dir>/<name>.sock        local socket (SOCK_SEQPACKET): open a session, ask for status
//   <prefix>S<id>_REQ        step_request_t                         client -> daemon (signed)
//   <prefix>S<id>_REPLY      sealed_t (step_reply_t, step_status_t, error_t)  daemon -> client
// <prefix> is "FAR_" for the daemon named "far", else "FAR_" + the name upper-cased with '-'
// as '_' + "_" ("gpu-1" -> "FAR_GPU_1_"). Receivers tell message types apart with
// IdentifyMessage.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace far::protocol {

/// The default LCM URL: multicast that never leaves the host (ttl=0). recv_buf_size lets
/// mid-size replies (up to the shm threshold) through without drops; see docs/protocol.md.
inline constexpr std::string_view kDefaultLcmUrl =
    "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152";

/// The name of a daemon started without --name.
inline constexpr std::string_view kDefaultDaemonName = "far";

/// True when `name` is 1..16 of [a-z0-9-] starting with a letter.
bool IsValidDaemonName(std::string_view name);

/// The LCM channel prefix of daemon `name` (@pre IsValidDaemonName).
std::string ChannelPrefix(std::string_view name);

/// Returns "<prefix>S<session_id>_REQ".
std::string SessionRequestChannel(std::string_view prefix, int64_t session_id);
/// Returns "<prefix>S<session_id>_REPLY".
std::string SessionReplyChannel(std::string_view prefix, int64_t session_id);
/// A regular expression (LCM subscribe syntax) matching every session request channel of the
/// daemon with this prefix.
std::string SessionRequestChannelPattern(std::string_view prefix);
/// Returns the session id of a "<prefix>S<id>_REQ" channel (id a decimal > 0 without leading
/// zeros, at most 18 digits), nullopt for any other name.
std::optional<int64_t> ParseSessionRequestChannel(std::string_view prefix,
                                                  std::string_view channel);

/// The directories where daemon sockets are looked for when none is given, in order:
/// $FAR_SOCKET_DIR alone when set (an absolute path); else /run/far when it exists (the
/// system service's RuntimeDirectory), $XDG_RUNTIME_DIR/far when that is set (a user's own
/// daemon), and PerUserSocketDirectory().path. Never empty.
std::vector<std::string> SocketDirectories();
/// The directory of daemon sockets when none is given: SocketDirectories().front(). A daemon
/// makes its socket there; a client tries it first and the others after it only when the
/// daemon there cannot hear it (far::client::Client::Connect).
std::string DefaultSocketDirectory();

/// The last choice of DefaultSocketDirectory, a directory no other user can take: /tmp/far-<uid>
/// while it is this user's (a directory, not a symbolic link, owned by this uid) or missing.
/// When another user holds that name (or it is a link or a file), $HOME/.far/run-<host> instead
/// ($HOME a directory of this user, not a link; <host> the host name, so that a home shared
/// between machines holds one per machine), and that one from then on while /tmp/far-<uid> is
/// missing (so that the other user cannot move it back by removing theirs). Without such a
/// $HOME, /tmp/far-<uid> all the same: the daemon then refuses it, naming its owner. The daemon
/// and its clients, of one uid and one environment, compute the same.
struct UserSocketDirectory {
  std::string path;
  /// Why /tmp/far-<uid> cannot be used ("/tmp/far-1000 belongs to uid 1001"), or "".
  std::string tmp_taken;
};
UserSocketDirectory PerUserSocketDirectory();
/// DefaultSocketDirectory() + "/" + name + ".sock".
std::string DefaultSocketPath(std::string_view name);

}  // namespace far::protocol
