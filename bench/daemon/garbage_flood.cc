#include "garbage_flood.h"

#include <time.h>

#include <chrono>
#include <random>

#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/session_auth.h"

namespace far::study {
namespace {

using Clock = std::chrono::steady_clock;

// Messages are made once: sending, not making, is what the flood should spend its time on.
constexpr int kMessages = 3000;

std::vector<uint8_t> RandomBytes(std::mt19937_64& random, size_t size) {
  std::vector<uint8_t> bytes(size);
  for (uint8_t& b : bytes) b = static_cast<uint8_t>(random());
  return bytes;
}

}  // namespace

Result<std::unique_ptr<GarbageFlood>> GarbageFlood::Start(const std::string& url,
                                                          const std::string& prefix, int64_t victim,
                                                          double per_second) {
  std::unique_ptr<GarbageFlood> flood(new GarbageFlood());
  auto bus = protocol::LcmBus::Create(url);
  if (!bus) return bus.error();
  flood->bus_ = std::move(*bus);
  std::mt19937_64 random(99);
  const std::string victim_channel = protocol::SessionRequestChannel(prefix, victim);
  protocol::SessionKey wrong_key{};
  for (uint8_t& b : wrong_key) b = static_cast<uint8_t>(random());
  StepRequest request;
  request.method = Method::kExact;
  for (int i = 0; i < kMessages; ++i) {
    switch (i % 3) {
      case 0:  // noise for the victim
        flood->messages_.push_back({victim_channel, RandomBytes(random, 8 + random() % 500)});
        break;
      case 1:  // noise for sessions that may or may not exist
        flood->messages_.push_back(
            {protocol::SessionRequestChannel(prefix, 1 + static_cast<int64_t>(random() % 100)),
             RandomBytes(random, 8 + random() % 500)});
        break;
      default: {  // a step request for the victim, signed with the wrong key
        auto message = protocol::MakeStepRequest(victim, 1'000'000 + i, i, 0, request);
        auto bytes = protocol::EncodeSigned(message, wrong_key);
        if (!bytes) return bytes.error();
        flood->messages_.push_back({victim_channel, std::move(*bytes)});
      }
    }
  }
  flood->thread_ = std::thread([raw = flood.get(), per_second] { raw->Run(per_second); });
  return flood;
}

// Sends what the rate allows so far, in batches, sleeping 100 us when ahead.
void GarbageFlood::Run(double per_second) {
  const auto start = Clock::now();
  size_t next = 0;
  while (!stop_) {
    const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
    const int64_t due = static_cast<int64_t>(elapsed * per_second) - report_.sent;
    if (due <= 0) {
      std::this_thread::sleep_for(std::chrono::microseconds(100));
      continue;
    }
    for (int64_t i = 0; i < std::min<int64_t>(due, 256); ++i) {
      const Message& message = messages_[next++ % messages_.size()];
      if (!bus_->Publish(message.channel, message.bytes)) ++report_.send_errors;
      ++report_.sent;
    }
  }
  report_.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  timespec cpu{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &cpu);
  report_.cpu_seconds = cpu.tv_sec + cpu.tv_nsec * 1e-9;
}

FloodReport GarbageFlood::Stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  return report_;
}

GarbageFlood::~GarbageFlood() { Stop(); }

}  // namespace far::study
