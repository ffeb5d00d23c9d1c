// Forged LCM datagrams against the receive path of the LCM built into far (docs/protocol.md,
// "The LCM receive path is untrusted input"). Debian's liblcm 1.3.1 died with SIGSEGV on the
// wrap-around fragment pair and delivered fragmented messages with missing, repeated or
// misplaced fragments with heap garbage in them; far's patched build drops all of these and
// still reassembles every genuine layout. Raw UDP to the test URL's multicast group, inside the
// test's own network namespace (loopback only).
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "daemon_fixture.h"
#include "integration_scenes.h"
#include "raw_session.h"
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>

#include "far/client/client.h"
#include "far/protocol/channels.h"
#include "far/protocol/lcm_bus.h"

namespace far::integration {
namespace {

using Bytes = std::vector<uint8_t>;

constexpr uint32_t kMagicShort = 0x4c433032;  // "LC02": one-datagram message
constexpr uint32_t kMagicLong = 0x4c433033;   // "LC03": one fragment of a message
// LCM_FRAGMENT_MAX_PAYLOAD on Linux: channel + NUL + data bytes of a full fragment.
constexpr uint32_t kFragmentPayload = 65487;

void PutU32(Bytes& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<uint8_t>(v >> shift));
}
void PutU16(Bytes& out, uint16_t v) {
  out.push_back(static_cast<uint8_t>(v >> 8));
  out.push_back(static_cast<uint8_t>(v));
}

// One fragment datagram: the 20-byte header, the channel and its NUL (fragment 0 only, when
// `channel` is not empty), then `data`.
Bytes Fragment(uint32_t seqno, uint32_t msg_size, uint32_t offset, uint16_t fragment_no,
               uint16_t fragments, std::string_view channel, std::span<const uint8_t> data) {
  Bytes out;
  PutU32(out, kMagicLong);
  PutU32(out, seqno);
  PutU32(out, msg_size);
  PutU32(out, offset);
  PutU16(out, fragment_no);
  PutU16(out, fragments);
  if (!channel.empty()) {
    out.insert(out.end(), channel.begin(), channel.end());
    out.push_back(0);
  }
  out.insert(out.end(), data.begin(), data.end());
  return out;
}

// The fragments a sender with fragment size `fragment_size` makes of `data` (LCM's C sender
// on Linux: kFragmentPayload; on macOS 1423; Java 64000).
std::vector<Bytes> FragmentsOf(uint32_t seqno, const std::string& channel,
                               std::span<const uint8_t> data,
                               uint32_t fragment_size = kFragmentPayload) {
  const size_t payload = channel.size() + 1 + data.size();
  const auto count = static_cast<uint16_t>((payload + fragment_size - 1) / fragment_size);
  const size_t first = fragment_size - channel.size() - 1;
  std::vector<Bytes> out;
  out.push_back(Fragment(seqno, static_cast<uint32_t>(data.size()), 0, 0, count, channel,
                         data.first(std::min(first, data.size()))));
  for (size_t offset = first, no = 1; offset < data.size(); offset += fragment_size, ++no) {
    const size_t size = std::min<size_t>(fragment_size, data.size() - offset);
    out.push_back(Fragment(seqno, static_cast<uint32_t>(data.size()), static_cast<uint32_t>(offset),
                           static_cast<uint16_t>(no), count, "", data.subspan(offset, size)));
  }
  return out;
}

Bytes Pattern(size_t size, uint32_t seed) {
  Bytes bytes(size);
  for (size_t i = 0; i < size; ++i) bytes[i] = static_cast<uint8_t>((i * 131 + seed) >> 3);
  return bytes;
}

// Datagrams from one UDP socket to the group and port of TestLcmUrl(). LCM reassembles per
// sender address and port, so each case below uses a sender of its own.
class RawSender {
 public:
  RawSender() {
    fd_ = socket(AF_INET, SOCK_DGRAM, 0);
    const uint8_t ttl = 0;  // like the URL's ttl=0: never past this host
    setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof(ttl));
    const std::string url = TestLcmUrl();  // udpm://<group>:<port>?...
    const size_t begin = url.find("://") + 3;
    const std::string address = url.substr(begin, url.find('?', begin) - begin);
    const size_t colon = address.find(':');
    destination_.sin_family = AF_INET;
    inet_aton(address.substr(0, colon).c_str(), &destination_.sin_addr);
    destination_.sin_port = htons(static_cast<uint16_t>(std::stoi(address.substr(colon + 1))));
  }
  ~RawSender() { close(fd_); }
  RawSender(const RawSender&) = delete;
  RawSender& operator=(const RawSender&) = delete;

  ::testing::AssertionResult Send(std::span<const uint8_t> datagram) {
    const ssize_t sent =
        sendto(fd_, datagram.data(), datagram.size(), 0,
               reinterpret_cast<const sockaddr*>(&destination_), sizeof(destination_));
    if (sent != static_cast<ssize_t>(datagram.size())) {
      return ::testing::AssertionFailure() << "sendto: " << std::strerror(errno);
    }
    // A pause per datagram: the receiver's socket buffer never overflows, so a message that
    // does not arrive was dropped by LCM, not by the kernel.
    usleep(2000);
    return ::testing::AssertionSuccess();
  }

 private:
  int fd_ = -1;
  sockaddr_in destination_{};
};

// The two datagrams of issue 10: fragment 0 of a 200000-byte message (a valid start), then
// fragment 1 at offset 0xFFFFFFF0 with 256 bytes. liblcm checked offset + size in 32 bits
// (0xFFFFFFF0 + 256 wraps to 240 <= 200000) and memcpy wrote 4 GiB past its buffer.
std::vector<Bytes> WrapAroundPair(uint32_t seqno, const std::string& channel) {
  const Bytes data(200000, 'A');
  const Bytes tail(256, 'B');
  std::vector<Bytes> fragments = FragmentsOf(seqno, channel, data);
  const auto count = static_cast<uint16_t>(fragments.size());
  return {fragments[0], Fragment(seqno, 200000, 0xFFFFFFF0u, 1, count, "", tail)};
}

// Datagrams that liblcm 1.3.1 turned into a delivered message although not every byte of it
// arrived (the rest was whatever malloc returned: issue 12's 0x41414141 "string length"), and
// datagrams too short for their own headers. Each needs a RawSender of its own.
std::vector<std::vector<Bytes>> IncompleteMessages(const std::string& channel) {
  const Bytes data(100000, 'A');  // two fragments
  const std::vector<Bytes> two = FragmentsOf(7, channel, data);
  std::vector<std::vector<Bytes>> cases;
  // fragments_in_msg says 1 for a 100000-byte message: "complete" after fragment 0.
  Bytes lie = two[0];
  lie[18] = 0;
  lie[19] = 1;
  cases.push_back({lie});
  // Fragment 0 twice: the plain counter reached 0 without fragment 1.
  cases.push_back({two[0], two[0]});
  // Fragment 1 at offset 0 instead of its own: in bounds, but a hole stays unwritten.
  Bytes misplaced = two[1];
  std::fill(misplaced.begin() + 12, misplaced.begin() + 16, 0);
  cases.push_back({two[0], misplaced});
  // Fragment 1 one byte short, and one byte longer, than the layout says.
  cases.push_back({two[0], Bytes(two[1].begin(), two[1].end() - 1)});
  Bytes longer = two[1];
  longer.push_back('A');
  cases.push_back({two[0], longer});
  // A datagram of 12 bytes with the fragment magic: shorter than the 20-byte header.
  cases.push_back({Bytes(two[0].begin(), two[0].begin() + 12)});
  // Fragment 0 whose channel name has no NUL inside the datagram.
  cases.push_back({Bytes(two[0].begin(), two[0].begin() + 20 + channel.size())});
  // A one-datagram message whose channel name has no NUL inside the datagram.
  Bytes unterminated;
  PutU32(unterminated, kMagicShort);
  PutU32(unterminated, 9);
  unterminated.insert(unterminated.end(), channel.begin(), channel.end());
  cases.push_back({unterminated});
  return cases;
}

// ---- reassembly through a real udpm socket, no daemon ------------------------------------------

constexpr std::string_view kTestChannel = "FAR_TEST_REASSEMBLY";

class LcmReassemblyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto listener = Listener::Create(TestLcmUrl());
    ASSERT_TRUE(listener.ok()) << far::ToString(listener.error());
    listener_ = std::move(*listener);
    listener_->Subscribe(std::string(kTestChannel) + ".*");
    listener_->Start();
  }
  // Publishes a short sentinel on `channel` and waits for it: every datagram sent before it
  // has been through LCM's receive thread by then (one socket, in order).
  ::testing::AssertionResult Sync(RawSender& sender, const std::string& channel) {
    Bytes sentinel;
    PutU32(sentinel, kMagicShort);
    PutU32(sentinel, 0);
    sentinel.insert(sentinel.end(), channel.begin(), channel.end());
    sentinel.push_back(0);
    const std::string_view text = "sentinel";
    sentinel.insert(sentinel.end(), text.begin(), text.end());
    if (auto sent = sender.Send(sentinel); !sent) return sent;
    auto got = listener_->WaitFor(
        [&](const Received& r) {
          return r.channel == channel && r.bytes == Bytes(text.begin(), text.end());
        },
        std::chrono::seconds(5));
    if (!got) return ::testing::AssertionFailure() << "the sentinel on " << channel << " is lost";
    return ::testing::AssertionSuccess();
  }
  std::unique_ptr<Listener> listener_;
};

TEST_F(LcmReassemblyTest, EveryGenuineFragmentLayoutArrivesByteForByte) {
  // LCM's own sender: 300000 bytes in five fragments.
  auto publisher = Listener::Create(TestLcmUrl());
  ASSERT_TRUE(publisher.ok());
  const std::string lcm_channel = std::string(kTestChannel) + "_LCM";
  const Bytes big = Pattern(300000, 1);
  ASSERT_TRUE((*publisher)->Publish(lcm_channel, big).ok());
  auto got = listener_->WaitFor([&](const Received& r) { return r.channel == lcm_channel; },
                                std::chrono::seconds(5));
  ASSERT_TRUE(got.has_value()) << "LCM's own fragmented message was not delivered";
  EXPECT_TRUE(got->bytes == big);

  // Other senders' fragment sizes, fragments 1.. in reverse order, and repeats after the end.
  struct Layout {
    uint32_t fragment_size;
    size_t bytes;
  };
  for (const Layout layout :
       {Layout{1423, 10000}, Layout{64000, 150000}, Layout{kFragmentPayload, kFragmentPayload},
        Layout{kFragmentPayload, 3 * kFragmentPayload}}) {
    SCOPED_TRACE(::testing::Message()
                 << layout.fragment_size << "-byte fragments, " << layout.bytes << " bytes");
    const std::string channel =
        std::string(kTestChannel) + "_" + std::to_string(layout.fragment_size);
    const Bytes data = Pattern(layout.bytes, layout.fragment_size);
    const std::vector<Bytes> fragments = FragmentsOf(42, channel, data, layout.fragment_size);
    RawSender sender;
    ASSERT_TRUE(sender.Send(fragments[0]));
    for (size_t i = fragments.size() - 1; i >= 1; --i) ASSERT_TRUE(sender.Send(fragments[i]));
    for (size_t i = 1; i < fragments.size(); ++i) ASSERT_TRUE(sender.Send(fragments[i]));
    ASSERT_TRUE(Sync(sender, channel));
    std::vector<Received> messages = listener_->Snapshot();
    ASSERT_EQ(messages.size(), 1u) << "one message, then nothing from the repeats";
    EXPECT_EQ(messages[0].channel, channel);
    EXPECT_TRUE(messages[0].bytes == data) << messages[0].bytes.size() << " bytes";
    listener_->Clear();
  }
}

TEST_F(LcmReassemblyTest, IncompleteOrInconsistentMessagesAreNeverDelivered) {
  const std::string channel(kTestChannel);
  for (const std::vector<Bytes>& datagrams : IncompleteMessages(channel)) {
    RawSender sender;
    for (const Bytes& datagram : datagrams) ASSERT_TRUE(sender.Send(datagram));
    ASSERT_TRUE(Sync(sender, channel));
  }
  // Sync took the sentinels; nothing else may have arrived.
  for (const Received& message : listener_->Snapshot()) {
    ADD_FAILURE() << "a " << message.bytes.size() << "-byte message on " << message.channel
                  << " was delivered";
  }
  // A genuine message from the same sender and sequence number as a dropped one completes.
  listener_->Clear();
  RawSender sender;
  const Bytes data(100000, 'A');
  const std::vector<Bytes> two = FragmentsOf(7, channel, data);
  ASSERT_TRUE(sender.Send(two[0]));
  ASSERT_TRUE(sender.Send(two[0]));  // a duplicate is dropped, the message still completes
  ASSERT_TRUE(sender.Send(two[1]));
  auto got = listener_->WaitFor([&](const Received& r) { return r.bytes.size() == data.size(); },
                                std::chrono::seconds(5));
  ASSERT_TRUE(got.has_value());
  EXPECT_TRUE(got->bytes == data);
}

TEST_F(LcmReassemblyTest, WrapAroundFragmentPairIsDropped) {
  const std::string channel(kTestChannel);
  RawSender sender;
  for (const Bytes& datagram : WrapAroundPair(3, channel)) ASSERT_TRUE(sender.Send(datagram));
  ASSERT_TRUE(Sync(sender, channel));  // this process's receive thread is still alive
  for (const Received& message : listener_->Snapshot()) {
    ADD_FAILURE() << "a " << message.bytes.size() << "-byte message was delivered";
  }
}

// A subscriber whose handler is behind (here: not running at all) while a burst of large
// datagrams arrives. Upstream's receive ring grew without bound (up to the subscription's queue
// capacity, 1000 datagrams of 60 KB: 60 MB) and never shrank; far's patch caps it at 4 MiB
// (with the fuller rings it replaced, about 14 MiB: ~230 datagrams of 60 KB) and drops the rest,
// and the subscriber receives again once it has caught up.
TEST(LcmReceiveRingTest, ASubscriberThatFallsBehindKeepsABoundedNumberOfLargeDatagrams) {
  const std::string channel = "FAR_TEST_RING";
  auto subscriber = protocol::LcmBus::Create(TestLcmUrl());
  auto publisher = protocol::LcmBus::Create(TestLcmUrl());
  ASSERT_TRUE(subscriber.ok() && publisher.ok());
  int received = 0;
  (*subscriber)->Subscribe(channel, [&](std::string_view, std::span<const uint8_t> bytes) {
    if (bytes.size() == 60'000) ++received;
  });
  const Bytes payload = Pattern(60'000, 7);
  constexpr int kBurst = 1000;
  // Paced, so that the kernel's socket buffer (a few such datagrams at net.core.rmem_max's
  // default) does not overflow first: what is dropped is dropped by LCM's receive ring.
  for (int i = 0; i < kBurst; ++i) {
    ASSERT_TRUE((*publisher)->Publish(channel, payload));
    std::this_thread::sleep_for(std::chrono::microseconds(300));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // all through the receive thread
  // Handle everything that was kept (one message per call) until nothing comes for 200 ms.
  for (int before = -1; received != before;) {
    before = received;
    (*subscriber)->Handle(std::chrono::milliseconds(200));
  }
  std::printf("%d of %d datagrams of 60 KB kept for a subscriber that was behind\n", received,
              kBurst);
  EXPECT_GE(received, 60) << "the receive ring holds at least 4 MiB";
  EXPECT_LE(received, 300) << "the receive ring held " << received << " x 60 KB";
  // Caught up: the next datagrams arrive again.
  received = 0;
  for (int i = 0; i < 10; ++i) ASSERT_TRUE((*publisher)->Publish(channel, payload));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (received < 10 && std::chrono::steady_clock::now() < deadline)
    (*subscriber)->Handle(std::chrono::milliseconds(100));
  EXPECT_EQ(received, 10);
}

// ---- against the daemon and its clients --------------------------------------------------------

using LcmForgedDatagramTest = DaemonTest;

TEST_F(LcmForgedDatagramTest, WrapAroundPairKillsNeitherTheDaemonNorItsClients) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  static const std::vector<SceneObject> kObjects = ContactSoup(kHealthySeed);
  const std::vector<ContactPair> expected = ReferenceContacts(kObjects);
  auto client = client::Client::Connect(TestClientOptions("under-attack"));
  ASSERT_TRUE(client.ok()) << far::ToString(client.error());
  Scene scene;
  scene.objects = kObjects;
  ASSERT_TRUE((*client)->LoadScene(scene).ok());

  // Every channel the daemon subscribes to, then the client's reply channel (the test process
  // itself receives there: with the unpatched LCM it dies here).
  uint32_t seqno = 100;
  for (const std::string& channel :
       {protocol::SessionRequestChannel("FAR_", (*client)->session_id()),
        protocol::SessionRequestChannel("FAR_", 999),
        protocol::SessionReplyChannel("FAR_", (*client)->session_id())}) {
    SCOPED_TRACE(channel);
    RawSender sender;
    for (const Bytes& datagram : WrapAroundPair(seqno++, channel)) {
      ASSERT_TRUE(sender.Send(datagram));
    }
    // A step sent after the pair is answered: both ends handled the pair and live on.
    auto step = (*client)->Step(SmallRequest());
    EXPECT_TRUE(step.ok()) << far::ToString(step.error());
    ASSERT_TRUE(daemon->Running()) << "far-daemon died:\n" << daemon->Log();
  }

  auto step = (*client)->Step(SmallRequest());
  ASSERT_TRUE(step.ok()) << far::ToString(step.error());
  EXPECT_EQ(step->contacts, expected);
  EXPECT_TRUE(HealthyClientSteps("after-wrap-around"));
  EXPECT_TRUE(daemon->Running());
}

TEST_F(LcmForgedDatagramTest, IncompleteFragmentedMessagesNeverReachTheDaemon) {
  DaemonProcess* daemon = StartDaemon();
  ASSERT_NE(daemon, nullptr);
  auto session = RawSession::Open(CurrentSocketPath(), TestLcmUrl(), "forged-fragments");
  ASSERT_TRUE(session.ok()) << far::ToString(session.error());
  RawSession& raw = **session;
  auto before = client::Client::Status(TestClientOptions("status"));
  ASSERT_TRUE(before.ok());

  // On the session's request channel liblcm 1.3.1 delivered each of these to the daemon (which
  // then quoted bytes of freed heap in an unsigned error): the patched LCM delivers none.
  for (const std::vector<Bytes>& datagrams : IncompleteMessages(raw.request_channel())) {
    RawSender sender;
    for (const Bytes& datagram : datagrams) ASSERT_TRUE(sender.Send(datagram));
  }
  // A step sent after them: its reply comes after any error they caused.
  ASSERT_TRUE(raw.writer().AddObject(1, TriangleRow(2), Motion::kRigid, Pose{}).ok());
  ASSERT_TRUE(raw.SendStep(1, SmallRequest()).ok());
  auto reply = raw.WaitStepReply(1);
  ASSERT_TRUE(reply.has_value());
  EXPECT_EQ(reply->status, 0) << reply->message;
  auto after = client::Client::Status(TestClientOptions("status"));
  ASSERT_TRUE(after.ok());
  EXPECT_EQ(after->rejected_messages_total, before->rejected_messages_total);
  EXPECT_TRUE(HealthyClientSteps("after-incomplete"));
  EXPECT_TRUE(daemon->Running());
}

}  // namespace
}  // namespace far::integration
