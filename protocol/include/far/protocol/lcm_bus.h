#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "far/base/result.h"

namespace far::protocol {

/// True for a URL whose messages stay inside one LCM instance: memq:// (each instance is its own
/// queue, so even another LcmBus in the same process never sees them). A daemon on such a URL
/// serves no client; it is for tests that drive the daemon's own bus.
inline bool IsInProcessUrl(std::string_view url) { return url.starts_with("memq://"); }

/// A thin owner of an LCM instance through LCM's C API. The C++ wrapper's subscribe is avoided:
/// its callback trampolines are miscompiled by GCC 12 under -fsanitize=vptr (docs/protocol.md),
/// and its typed handlers decode without our size guards. Handlers get raw bytes.
///
/// Thread safety: Publish, Subscribe and Unsubscribe may be called from any thread, also while
/// another handles; Handle from one thread only, which runs the handlers.
class LcmBus {
 public:
  using Handler = std::function<void(std::string_view channel, std::span<const uint8_t> bytes)>;
  using SubscriptionId = uint64_t;

  /// Connects to `url` (e.g. "udpm://239.255.76.67:7667?ttl=0", "memq://").
  /// Errors: kInvalidArgument for any other provider (far's LCM has only these two);
  /// kUnavailable naming the URL (bad URL, no multicast route on loopback, ...).
  static Result<std::unique_ptr<LcmBus>> Create(const std::string& url);
  ~LcmBus();
  LcmBus(const LcmBus&) = delete;
  LcmBus& operator=(const LcmBus&) = delete;

  /// Messages LCM keeps per subscription while they wait for Handle. LCM's default is 30 and
  /// it silently drops what does not fit: the daemon's one subscription for every session's
  /// request channel would lose a well-behaved session's step request after a burst of 30
  /// messages from another session (tests/integration: BurstFromOneSession...). Memory bound:
  /// this many received messages, and at most 4 MiB of single-datagram ones in far's LCM
  /// (its receive ring; about 14 MiB with the rings it replaced while they drain), given back
  /// once they are handled (docs/protocol.md, "What the patched receive path guarantees").
  static constexpr int kQueueCapacity = 1000;

  /// Calls `handler` for every message on channels matching the regular expression `channel`
  /// (queue capacity kQueueCapacity), from now on. Returns the subscription's id (never 0).
  SubscriptionId Subscribe(const std::string& channel, Handler handler);
  /// Ends subscription `id`: no message is passed to its handler after this returns, but the
  /// one the handling thread may be passing to it right now (a caller that frees what the
  /// handler uses waits for that call itself). An unknown id is ignored.
  void Unsubscribe(SubscriptionId id);
  /// Publishes bytes on `channel`. Errors: kUnavailable when LCM fails to send.
  Result<void> Publish(const std::string& channel, std::span<const uint8_t> bytes);
  /// Waits up to `timeout` for messages and runs their handlers. Returns false on an LCM error.
  bool Handle(std::chrono::milliseconds timeout);

  const std::string& url() const { return url_; }

 private:
  LcmBus() = default;
  std::string url_;
  void* lcm_ = nullptr;  // lcm_t*
  std::mutex publish_mutex_;
  std::mutex subscriptions_mutex_;
  std::map<SubscriptionId, void*> subscriptions_;  // lcm_subscription_t*, by id
};

}  // namespace far::protocol
