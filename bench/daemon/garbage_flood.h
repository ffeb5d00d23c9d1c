#pragma once

// A flood of LCM datagrams no daemon may answer, sent from a thread with an LCM instance of
// its own at a target rate: random bytes on the victim session's request channel and on other
// session channels, and well-formed step_request_t for the victim session signed with a wrong
// key (they decode, find the session, and fail authentication: the dearest path to drop).

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "far/base/result.h"
#include "far/protocol/lcm_bus.h"

namespace far::study {

struct FloodReport {
  int64_t sent = 0;
  int64_t send_errors = 0;
  double seconds = 0;
  double cpu_seconds = 0;  ///< the sending thread's CPU time
  double Rate() const { return seconds > 0 ? sent / seconds : 0; }
};

class GarbageFlood {
 public:
  /// Starts sending at `per_second` messages on `url` to the sessions of the daemon whose
  /// channel prefix is `prefix`, aiming at session `victim`.
  static Result<std::unique_ptr<GarbageFlood>> Start(const std::string& url,
                                                     const std::string& prefix, int64_t victim,
                                                     double per_second);
  ~GarbageFlood();
  /// Stops and says what was sent.
  FloodReport Stop();

 private:
  struct Message {
    std::string channel;
    std::vector<uint8_t> bytes;
  };
  GarbageFlood() = default;
  void Run(double per_second);
  std::unique_ptr<protocol::LcmBus> bus_;
  std::vector<Message> messages_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  FloodReport report_;
};

}  // namespace far::study
