#include "far/protocol/lcm_bus.h"

#include <atomic>
#include <cstdint>
#include <unordered_map>

#include <lcm/lcm.h>

namespace far::protocol {
namespace {

// The handlers of every subscription in the process, by id. LCM passes a subscription's
// userdata to its handler after releasing its own lock, so an unsubscribe on another thread
// may come in between: the userdata is the id, never a pointer that could be freed by then.
std::mutex g_handlers_mutex;
std::unordered_map<uint64_t, std::shared_ptr<const LcmBus::Handler>> g_handlers;
std::atomic<uint64_t> g_next_id{1};

void Dispatch(const lcm_recv_buf_t* buffer, const char* channel, void* id) {
  std::shared_ptr<const LcmBus::Handler> handler;
  {
    std::lock_guard lock(g_handlers_mutex);
    auto it = g_handlers.find(reinterpret_cast<uintptr_t>(id));
    if (it == g_handlers.end()) return;
    handler = it->second;
  }
  (*handler)(channel, std::span<const uint8_t>(static_cast<const uint8_t*>(buffer->data),
                                               buffer->data_size));
}

}  // namespace

Result<std::unique_ptr<LcmBus>> LcmBus::Create(const std::string& url) {
  // Only the providers far builds and has hardened (docs/protocol.md). An empty URL would let
  // LCM take $LCM_DEFAULT_URL instead.
  if (!url.starts_with("udpm://") && !url.starts_with("memq://")) {
    return MakeError(ErrorCode::kInvalidArgument,
                     "LCM URL '" + url +
                         "': far accepts only the udpm:// and memq:// providers (file://, "
                         "tcpq:// and mpudpm:// are not built in)");
  }
  lcm_t* lcm = lcm_create(url.c_str());
  if (lcm == nullptr) {
    return MakeError(ErrorCode::kUnavailable,
                     "LCM cannot start on '" + url +
                         "' (for udpm, loopback needs multicast: ip link set lo multicast on; "
                         "ip route add 224.0.0.0/4 dev lo)");
  }
  std::unique_ptr<LcmBus> bus(new LcmBus());
  bus->url_ = url;
  bus->lcm_ = lcm;
  return bus;
}

LcmBus::~LcmBus() {
  std::map<SubscriptionId, void*> left;
  {
    std::lock_guard lock(subscriptions_mutex_);
    left = subscriptions_;
  }
  for (const auto& [id, subscription] : left) Unsubscribe(id);
  lcm_destroy(static_cast<lcm_t*>(lcm_));
}

LcmBus::SubscriptionId LcmBus::Subscribe(const std::string& channel, Handler handler) {
  const SubscriptionId id = g_next_id.fetch_add(1);
  {
    std::lock_guard lock(g_handlers_mutex);
    g_handlers.emplace(id, std::make_shared<const Handler>(std::move(handler)));
  }
  lcm_subscription_t* subscription = lcm_subscribe(static_cast<lcm_t*>(lcm_), channel.c_str(),
                                                   &Dispatch, reinterpret_cast<void*>(id));
  if (subscription != nullptr) {
    lcm_subscription_set_queue_capacity(subscription, kQueueCapacity);
    std::lock_guard lock(subscriptions_mutex_);
    subscriptions_.emplace(id, subscription);
  }
  return id;
}

void LcmBus::Unsubscribe(SubscriptionId id) {
  void* subscription = nullptr;
  {
    std::lock_guard lock(subscriptions_mutex_);
    auto it = subscriptions_.find(id);
    if (it != subscriptions_.end()) {
      subscription = it->second;
      subscriptions_.erase(it);
    }
  }
  if (subscription != nullptr)
    lcm_unsubscribe(static_cast<lcm_t*>(lcm_), static_cast<lcm_subscription_t*>(subscription));
  std::lock_guard lock(g_handlers_mutex);
  g_handlers.erase(id);
}

Result<void> LcmBus::Publish(const std::string& channel, std::span<const uint8_t> bytes) {
  // An empty span's data() may be null, and memq copies the payload with memcpy, whose
  // pointers must never be null (even for 0 bytes): give LCM a valid address.
  static constexpr uint8_t kNoBytes = 0;
  const uint8_t* data = bytes.empty() ? &kNoBytes : bytes.data();
  std::lock_guard lock(publish_mutex_);
  if (lcm_publish(static_cast<lcm_t*>(lcm_), channel.c_str(), data,
                  static_cast<unsigned int>(bytes.size())) != 0) {
    return MakeError(
        ErrorCode::kUnavailable,
        "LCM could not publish " + std::to_string(bytes.size()) + " bytes on " + channel);
  }
  return {};
}

bool LcmBus::Handle(std::chrono::milliseconds timeout) {
  return lcm_handle_timeout(static_cast<lcm_t*>(lcm_), static_cast<int>(timeout.count())) >= 0;
}

}  // namespace far::protocol
