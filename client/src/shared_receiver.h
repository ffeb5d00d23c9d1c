#pragma once

// One LCM instance and one receiving thread per LCM URL in a process, shared by every Client on
// that URL. LCM over UDP multicast hands every datagram on the group to every LCM instance
// (each has its own socket and receive thread, which reads it and drops what no subscription
// wants): with an instance per Client, 8 Clients in one process made each step's datagrams
// wake 8 receive threads of that process. With one instance, each datagram is read once per
// process, and only its session's subscription passes it on.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>

#include "far/base/result.h"
#include "far/protocol/lcm_bus.h"

namespace far::client::internal {

class SharedReceiver {
 public:
  /// How often every listener's on_tick runs (and the longest the thread waits for LCM).
  static constexpr std::chrono::milliseconds kTickEvery{50};

  /// The receiver of `url` in this process, created (LCM instance and thread) when there is
  /// none; it ends when the last holder lets it go. Errors: those of protocol::LcmBus::Create.
  static Result<std::shared_ptr<SharedReceiver>> For(const std::string& url);
  ~SharedReceiver();
  SharedReceiver(const SharedReceiver&) = delete;
  SharedReceiver& operator=(const SharedReceiver&) = delete;

  struct Listener {
    /// Each message on the listener's channel.
    std::function<void(std::span<const uint8_t> bytes)> on_message;
    /// Every kTickEvery: the listener's timers (asking again, a closed connection).
    std::function<void()> on_tick;
  };
  using ListenerId = uint64_t;

  /// Passes the messages of `channel` (an exact name) to `listener` on the receiving thread,
  /// from now on. Any thread.
  ListenerId Attach(const std::string& channel, Listener listener);
  /// Stops passing messages and ticks to listener `id`. When it returns, none of its callbacks
  /// runs or will run, except the one that called Detach on the receiving thread itself.
  void Detach(ListenerId id);
  /// Publishes on the shared LCM instance. Any thread.
  Result<void> Publish(const std::string& channel, std::span<const uint8_t> bytes);
  /// True on the receiving thread (where every listener's callbacks run).
  bool OnReceivingThread() const { return std::this_thread::get_id() == thread_id_; }

 private:
  explicit SharedReceiver(std::unique_ptr<protocol::LcmBus> bus);
  void Run();
  // Runs `call` for listener `id` unless it was detached; Detach waits while it runs.
  void Call(ListenerId id, const std::function<void(const Listener&)>& call);

  std::unique_ptr<protocol::LcmBus> bus_;
  std::mutex mutex_;
  std::condition_variable done_;
  struct Entry {
    std::shared_ptr<const Listener> listener;
    protocol::LcmBus::SubscriptionId subscription = 0;
  };
  std::map<ListenerId, Entry> listeners_;  // under mutex_
  ListenerId next_id_ = 1;                 // under mutex_
  ListenerId calling_ = 0;                 // under mutex_: whose callback runs now (0: none)
  bool stopping_ = false;                  // under mutex_
  std::thread thread_;
  std::thread::id thread_id_;
};

}  // namespace far::client::internal
