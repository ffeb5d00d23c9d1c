#include "shared_receiver.h"

#include <vector>

namespace far::client::internal {
namespace {

using Clock = std::chrono::steady_clock;

// The live receivers by URL. weak_ptr: a receiver ends with its last Client, not the process.
std::mutex g_receivers_mutex;
std::map<std::string, std::weak_ptr<SharedReceiver>> g_receivers;

}  // namespace

Result<std::shared_ptr<SharedReceiver>> SharedReceiver::For(const std::string& url) {
  std::lock_guard lock(g_receivers_mutex);
  if (auto live = g_receivers[url].lock()) return live;
  auto bus = protocol::LcmBus::Create(url);
  if (!bus) return bus.error();
  std::shared_ptr<SharedReceiver> receiver(new SharedReceiver(std::move(*bus)));
  g_receivers[url] = receiver;
  // Forget the URLs whose receivers ended (a process that moves between URLs).
  std::erase_if(g_receivers, [](const auto& entry) { return entry.second.expired(); });
  return receiver;
}

SharedReceiver::SharedReceiver(std::unique_ptr<protocol::LcmBus> bus) : bus_(std::move(bus)) {
  // LCM's udpm provider makes its sockets, receive thread and the mutexes guarding them lazily,
  // on the first subscribe or handle, and that first time is not safe from two threads at
  // once (ThreadSanitizer: a subscribe racing the handling thread's first wait). A handle
  // that returns at once makes them here, before the handling thread exists.
  bus_->Handle(std::chrono::milliseconds(0));
  // Run takes the lock first: it sees thread_id_ set.
  std::lock_guard lock(mutex_);
  thread_ = std::thread([this] { Run(); });
  thread_id_ = thread_.get_id();
}

SharedReceiver::~SharedReceiver() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  thread_.join();
}

SharedReceiver::ListenerId SharedReceiver::Attach(const std::string& channel, Listener listener) {
  ListenerId id = 0;
  {
    std::lock_guard lock(mutex_);
    id = next_id_++;
    listeners_[id].listener = std::make_shared<const Listener>(std::move(listener));
  }
  // The subscription's handler finds the listener by id: after Detach it finds none.
  const auto subscription =
      bus_->Subscribe(channel, [this, id](std::string_view, std::span<const uint8_t> bytes) {
        Call(id, [bytes](const Listener& listener) { listener.on_message(bytes); });
      });
  std::lock_guard lock(mutex_);
  if (auto it = listeners_.find(id); it != listeners_.end()) it->second.subscription = subscription;
  return id;
}

void SharedReceiver::Detach(ListenerId id) {
  protocol::LcmBus::SubscriptionId subscription = 0;
  {
    std::unique_lock lock(mutex_);
    auto it = listeners_.find(id);
    if (it == listeners_.end()) return;
    subscription = it->second.subscription;
    listeners_.erase(it);
    if (!OnReceivingThread()) done_.wait(lock, [&] { return calling_ != id; });
  }
  bus_->Unsubscribe(subscription);
}

Result<void> SharedReceiver::Publish(const std::string& channel, std::span<const uint8_t> bytes) {
  return bus_->Publish(channel, bytes);
}

void SharedReceiver::Call(ListenerId id, const std::function<void(const Listener&)>& call) {
  std::shared_ptr<const Listener> listener;
  {
    std::lock_guard lock(mutex_);
    auto it = listeners_.find(id);
    if (it == listeners_.end()) return;
    listener = it->second.listener;
    calling_ = id;
  }
  call(*listener);
  {
    std::lock_guard lock(mutex_);
    calling_ = 0;
  }
  done_.notify_all();
}

void SharedReceiver::Run() {
  auto next_tick = Clock::now() + kTickEvery;
  for (;;) {
    {
      std::lock_guard lock(mutex_);
      if (stopping_) return;
    }
    const auto now = Clock::now();
    if (now >= next_tick) {
      std::vector<ListenerId> ids;
      {
        std::lock_guard lock(mutex_);
        for (const auto& [id, entry] : listeners_) ids.push_back(id);
      }
      for (ListenerId id : ids) Call(id, [](const Listener& listener) { listener.on_tick(); });
      next_tick = Clock::now() + kTickEvery;
      continue;
    }
    const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(next_tick - now);
    bus_->Handle(std::max(wait, std::chrono::milliseconds(1)));
  }
}

}  // namespace far::client::internal
