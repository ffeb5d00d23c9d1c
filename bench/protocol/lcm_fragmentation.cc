// LCM fragmentation study: do large step replies arrive whole, and how fast?
//
// Publishes step_reply_t messages with N contact pairs (1k .. 100k) and measures, per
// transport, how many arrive and the end-to-end latency (encode + sign + publish + receive +
// decode + verify, and for the shm path the ring write, read and hash):
//   udpm            LCM multicast on loopback with the kernel's default receive buffer
//   udpm+rbuf       the same with recv_buf_size (SO_RCVBUF) in the URL
//   memq            LCM's in-process queue (no kernel, no fragmentation: the floor)
//   shm             the full reply in the segment's reply ring, a signed stub over udpm
// Two patterns: "seq" sends one reply and waits for it (request/reply), "burst" sends 10
// back-to-back (a daemon answering several clients) and counts what arrives.
//
// udpm must never leave the machine: run it in a private network namespace, e.g.
//   unshare -rn bash -c 'ip link set lo up; ip link set lo multicast on;
//     ip route add 224.0.0.0/4 dev lo; ./far_lcm_fragmentation'   (one line)
// (as root `unshare -n` suffices). Results and the decision they support: docs/protocol.md.

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "far/protocol/convert.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/shm_reply.h"
#include "far/protocol/shm_segment.h"

namespace far::protocol {
namespace {

using Clock = std::chrono::steady_clock;

constexpr const char* kChannel = "FAR_S1_REPLY";
constexpr int kMessages = 50;
constexpr int kBurst = 10;

far_lcm::step_reply_t MakeReply(int pairs, int64_t request_id) {
  StepResult result;
  result.contacts.reserve(static_cast<size_t>(pairs));
  for (int i = 0; i < pairs; ++i) {
    result.contacts.push_back({static_cast<uint32_t>(i % 1000), static_cast<uint32_t>(i),
                               static_cast<uint32_t>(1000 + i % 17), static_cast<uint32_t>(7 * i)});
  }
  auto reply = MakeStepReply({1, request_id, request_id, 0}, Output::kContacts, result);
  if (!reply) {
    std::fprintf(stderr, "MakeStepReply: %s\n", reply.error().message.c_str());
    std::exit(1);
  }
  return *reply;
}

// Receives step replies on one LCM instance in its own thread and records arrival times.
class Receiver {
 public:
  Receiver(lcm::LCM* lcm, const SessionKey& key, RingReader* replies)
      : lcm_(lcm), key_(key), replies_(replies) {
    lcm_->subscribe(kChannel, &Receiver::Handle, this);
  }

  void Handle(const lcm::ReceiveBuffer* buffer, const std::string&) {
    auto reply = ReceiveStepReply(buffer->data, buffer->data_size, key_, *replies_);
    const auto now = Clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    if (!reply) {
      ++errors_;
      last_error_ = reply.error().message;
    } else {
      arrivals_[reply->request_id] = now;
      contacts_[reply->request_id] = reply->num_contacts;
    }
    changed_.notify_all();
  }

  // Waits until request `id` arrived or `timeout` passed.
  std::optional<Clock::time_point> WaitFor(int64_t id, std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    changed_.wait_for(lock, timeout, [&] { return arrivals_.count(id) != 0; });
    auto it = arrivals_.find(id);
    if (it == arrivals_.end()) return std::nullopt;
    return it->second;
  }
  int CountIn(int64_t first, int64_t last) {
    std::lock_guard<std::mutex> lock(mutex_);
    int count = 0;
    for (int64_t id = first; id <= last; ++id) count += arrivals_.count(id) != 0 ? 1 : 0;
    return count;
  }
  int errors() {
    std::lock_guard<std::mutex> lock(mutex_);
    return errors_;
  }
  std::string last_error() {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_error_;
  }

 private:
  lcm::LCM* lcm_;
  SessionKey key_;
  RingReader* replies_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<int64_t, Clock::time_point> arrivals_;
  std::map<int64_t, int> contacts_;
  int errors_ = 0;
  std::string last_error_;
};

struct Row {
  std::string transport;
  int pairs = 0;
  size_t bytes = 0;
  int seq_delivered = 0;
  double median_ms = -1;
  double p90_ms = -1;
  int burst_delivered = 0;
};

double Percentile(std::vector<double> values, double q) {
  if (values.empty()) return -1;
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(q * static_cast<double>(values.size() - 1))];
}

// Runs one transport at one size. `url` empty: memq in process.
Row Measure(const std::string& transport, const std::string& url, bool shm, int pairs) {
  Row row;
  row.transport = transport;
  row.pairs = pairs;

  // A session segment with a 64 MiB reply ring (room for a burst of 100k-pair replies).
  auto segment = ShmSegment::Create(1, {kMinRingCapacity, uint64_t{1} << 26});
  if (!segment) {
    std::fprintf(stderr, "segment: %s\n", segment.error().message.c_str());
    std::exit(1);
  }
  auto client_segment = ShmSegment::Open((*segment)->name(), 1);
  if (!client_segment) {
    std::fprintf(stderr, "segment: %s\n", client_segment.error().message.c_str());
    std::exit(1);
  }
  RingWriter daemon_replies((*segment)->reply_ring());
  RingReader client_replies((*client_segment)->reply_ring(), kMaxStepReplyBytes);
  const SessionKey key = (*segment)->session_key();

  const bool memq = url.empty();
  lcm::LCM publisher(memq ? "memq://" : url);
  std::unique_ptr<lcm::LCM> subscriber_storage;
  if (!memq) subscriber_storage = std::make_unique<lcm::LCM>(url);
  lcm::LCM* subscriber = memq ? &publisher : subscriber_storage.get();
  if (!publisher.good() || !subscriber->good()) {
    std::fprintf(stderr, "lcm: cannot open %s (multicast on lo? see the top of this file)\n",
                 url.c_str());
    std::exit(1);
  }
  Receiver receiver(subscriber, key, &client_replies);
  bool stop = false;
  std::thread pump;
  if (!memq) {
    pump = std::thread([&] {
      while (!stop) subscriber->handleTimeout(20);
    });
  }

  // The reply is built once (the daemon has its result); the clock covers what a reply costs
  // from there: encode, sign, publish (or ring write + stub), receive, verify, decode.
  far_lcm::step_reply_t full = MakeReply(pairs, 0);
  // Encodes, signs and publishes reply `id`; the shm path writes it into the ring first.
  auto send = [&](int64_t id) {
    full.request_id = id;
    full.step_id = id;
    std::vector<uint8_t> bytes;
    if (shm) {
      auto encoded = EncodeMessage(full);
      auto ref = WriteShmReply(daemon_replies, *encoded);
      if (!ref) {
        std::fprintf(stderr, "shm: %s\n", ref.error().message.c_str());
        return size_t{0};
      }
      bytes = *EncodeSigned(MakeShmReplyStub(full, *ref), key);
      row.bytes = encoded->size();
    } else {
      bytes = *EncodeMessage(full);
      (void)SignEncoded(bytes, key);
      row.bytes = bytes.size();
    }
    publisher.publish(kChannel, bytes.data(), static_cast<unsigned>(bytes.size()));
    if (memq) publisher.handleTimeout(0);
    return bytes.size();
  };

  // Sequential: one in flight.
  std::vector<double> latencies;
  for (int i = 1; i <= kMessages; ++i) {
    const auto start = Clock::now();
    send(i);
    auto arrived = receiver.WaitFor(i, std::chrono::milliseconds(300));
    if (arrived) {
      ++row.seq_delivered;
      latencies.push_back(std::chrono::duration<double, std::milli>(*arrived - start).count());
    }
  }
  row.median_ms = Percentile(latencies, 0.5);
  row.p90_ms = Percentile(latencies, 0.9);

  // Burst: kBurst back-to-back, then give them time to arrive.
  const int64_t first = 1000;
  for (int i = 0; i < kBurst; ++i) send(first + i);
  if (memq) {
    while (publisher.handleTimeout(0) > 0) {
    }
  }
  receiver.WaitFor(first + kBurst - 1, std::chrono::milliseconds(1000));
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  row.burst_delivered = receiver.CountIn(first, first + kBurst - 1);

  stop = true;
  if (pump.joinable()) pump.join();
  if (receiver.errors() > 0) {
    std::fprintf(stderr, "%s %d: %d receive errors, last: %s\n", transport.c_str(), pairs,
                 receiver.errors(), receiver.last_error().c_str());
  }
  return row;
}

// Median wall time of `f` over `runs` runs, in milliseconds.
template <typename F>
double MedianMs(int runs, F&& f) {
  std::vector<double> times;
  for (int i = 0; i < runs; ++i) {
    const auto start = Clock::now();
    f();
    times.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  return Percentile(times, 0.5);
}

// Where the time of a large reply goes, without any transport.
void PrintCosts(const std::vector<int>& sizes) {
  std::printf("\n%-8s %10s %9s %9s %9s %9s %9s\n", "pairs", "bytes", "encode", "sign", "verify",
              "decode", "hash");
  for (const int pairs : sizes) {
    const auto full = MakeReply(pairs, 1);
    const SessionKey key = NewSessionKey();
    std::vector<uint8_t> bytes = *EncodeMessage(full);
    const double encode = MedianMs(11, [&] { bytes = *EncodeMessage(full); });
    const double sign = MedianMs(11, [&] { (void)SignEncoded(bytes, key); });
    const double verify = MedianMs(11, [&] { (void)VerifyEncoded(bytes, key); });
    const double decode = MedianMs(11, [&] {
      auto decoded =
          DecodeMessage<far_lcm::step_reply_t>(bytes.data(), bytes.size(), kMaxStepReplyBytes);
      if (!decoded) std::exit(1);
    });
    const double hash = MedianMs(11, [&] { (void)HashBytes(bytes); });
    std::printf("%-8d %10zu %9.3f %9.3f %9.3f %9.3f %9.3f\n", pairs, bytes.size(), encode, sign,
                verify, decode, hash);
  }
}

int Main(int argc, char** argv) {
  const std::string base = "udpm://239.255.76.67:7667?ttl=0";
  std::vector<int> sizes = {1000, 4000, 10000, 50000, 100000};
  if (argc > 1) {
    sizes.clear();
    for (int i = 1; i < argc; ++i) sizes.push_back(std::atoi(argv[i]));
  }
  struct Transport {
    std::string name;
    std::string url;
    bool shm;
  };
  const std::vector<Transport> transports = {
      {"udpm", base, false},
      {"udpm+rbuf2M", base + "&recv_buf_size=2097152", false},
      {"udpm+rbuf8M", base + "&recv_buf_size=8388608", false},
      {"memq", "", false},
      {"shm+udpm stub", base, true},
  };
  std::printf("%-14s %8s %10s %9s %10s %9s %9s\n", "transport", "pairs", "bytes", "seq ok",
              "median ms", "p90 ms", "burst ok");
  for (const int pairs : sizes) {
    for (const Transport& t : transports) {
      const Row row = Measure(t.name, t.url, t.shm, pairs);
      std::printf("%-14s %8d %10zu %6d/%-2d %10.3f %9.3f %6d/%-2d\n", row.transport.c_str(),
                  row.pairs, row.bytes, row.seq_delivered, kMessages, row.median_ms, row.p90_ms,
                  row.burst_delivered, kBurst);
      std::fflush(stdout);
    }
  }
  PrintCosts(sizes);
  return 0;
}

}  // namespace
}  // namespace far::protocol

int main(int argc, char** argv) { return far::protocol::Main(argc, argv); }
