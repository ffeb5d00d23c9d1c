#include "far/protocol/lcm_bus.h"

#include <lcm/lcm.h>

namespace far::protocol {

struct LcmBus::Subscription {
  Handler handler;
  lcm_subscription_t* lcm_subscription = nullptr;

  static void Dispatch(const lcm_recv_buf_t* buffer, const char* channel, void* self) {
    const auto* subscription = static_cast<const Subscription*>(self);
    subscription->handler(
        channel,
        std::span<const uint8_t>(static_cast<const uint8_t*>(buffer->data), buffer->data_size));
  }
};

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
  auto* lcm = static_cast<lcm_t*>(lcm_);
  for (auto& subscription : subscriptions_) lcm_unsubscribe(lcm, subscription->lcm_subscription);
  lcm_destroy(lcm);
}

void LcmBus::Subscribe(const std::string& channel, Handler handler) {
  auto subscription = std::make_unique<Subscription>();
  subscription->handler = std::move(handler);
  subscription->lcm_subscription = lcm_subscribe(static_cast<lcm_t*>(lcm_), channel.c_str(),
                                                 &Subscription::Dispatch, subscription.get());
  if (subscription->lcm_subscription != nullptr) {
    lcm_subscription_set_queue_capacity(subscription->lcm_subscription, kQueueCapacity);
  }
  subscriptions_.push_back(std::move(subscription));
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
