#pragma once

// LCM channel names. One channel per purpose; per session one request and one reply channel.
//   FAR_OPEN                  open_session_t             client -> daemon
//   FAR_OPEN_REPLY_<suffix>   open_session_reply_t       daemon -> client (client picks suffix)
//   FAR_S<id>_REQ             step_request_t, heartbeat_t, close_session_t   client -> daemon
//   FAR_S<id>_REPLY           step_reply_t, heartbeat_t, error_t             daemon -> client
//   FAR_STATUS                status_request_t           anyone -> daemon
//   FAR_STATUS_REPLY          status_reply_t             daemon -> anyone
// Several types share a session channel; receivers tell them apart with IdentifyMessage.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace far::protocol {

/// The default LCM URL: multicast that never leaves the host (ttl=0). recv_buf_size lets
/// mid-size replies (up to the shm threshold) through without drops; see docs/protocol.md.
inline constexpr std::string_view kDefaultLcmUrl =
    "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=2097152";

inline constexpr std::string_view kOpenChannel = "FAR_OPEN";
inline constexpr std::string_view kOpenReplyPrefix = "FAR_OPEN_REPLY_";
inline constexpr std::string_view kStatusChannel = "FAR_STATUS";
inline constexpr std::string_view kStatusReplyChannel = "FAR_STATUS_REPLY";
/// A regular expression (LCM subscribe syntax) matching every session request channel.
inline constexpr std::string_view kSessionRequestChannelPattern = "FAR_S[0-9]+_REQ";

/// Returns "FAR_S<session_id>_REQ".
std::string SessionRequestChannel(int64_t session_id);
/// Returns "FAR_S<session_id>_REPLY".
std::string SessionReplyChannel(int64_t session_id);
/// Returns the session id of a "FAR_S<id>_REQ" channel (id a decimal > 0 without leading
/// zeros, at most 18 digits), nullopt for any other name.
std::optional<int64_t> ParseSessionRequestChannel(std::string_view channel);
/// True when `channel` is kOpenReplyPrefix followed by 1..48 of [A-Za-z0-9_-]. The daemon
/// only answers on such channels, so a client cannot make it publish on a session's channel.
bool IsValidOpenReplyChannel(std::string_view channel);

}  // namespace far::protocol
