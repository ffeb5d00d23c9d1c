// LcmBus accepts only the LCM providers far builds and hardened (udpm, memq; docs/protocol.md).
#include "far/protocol/lcm_bus.h"

#include <chrono>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace far::protocol {
namespace {

TEST(LcmBusTest, RefusesProvidersFarDoesNotBuild) {
  for (const char* url :
       {"file:///tmp/far.log?mode=r", "tcpq://127.0.0.1:7700", "mpudpm://239.255.76.67:7667", "",
        "UDPM://239.255.76.67:7667", "udpm:239.255.76.67:7667"}) {
    SCOPED_TRACE(url);
    auto bus = LcmBus::Create(url);
    ASSERT_FALSE(bus.ok());
    EXPECT_EQ(bus.error().code, ErrorCode::kInvalidArgument);
    EXPECT_NE(bus.error().message.find("only the udpm:// and memq:// providers"), std::string::npos)
        << bus.error().message;
  }
}

TEST(LcmBusTest, MemqDeliversWhatWasPublished) {
  auto bus = LcmBus::Create("memq://");
  ASSERT_TRUE(bus.ok()) << ToString(bus.error());
  std::vector<uint8_t> got;
  (*bus)->Subscribe("FAR_TEST", [&](std::string_view, std::span<const uint8_t> bytes) {
    got.assign(bytes.begin(), bytes.end());
  });
  const std::vector<uint8_t> sent = {1, 2, 3, 4};
  ASSERT_TRUE((*bus)->Publish("FAR_TEST", sent).ok());
  ASSERT_TRUE((*bus)->Handle(std::chrono::seconds(1)));
  EXPECT_EQ(got, sent);
}

// Found by the daemon_datagram fuzz target: an empty span's data() is null, and memq's
// memcpy(dst, NULL, 0) is undefined behaviour (UBSan's nonnull-attribute check in the asan build).
TEST(LcmBusTest, MemqDeliversAnEmptyMessage) {
  auto bus = LcmBus::Create("memq://");
  ASSERT_TRUE(bus.ok()) << ToString(bus.error());
  int delivered = 0;
  size_t size = 1;
  (*bus)->Subscribe("FAR_TEST", [&](std::string_view, std::span<const uint8_t> bytes) {
    ++delivered;
    size = bytes.size();
  });
  ASSERT_TRUE((*bus)->Publish("FAR_TEST", std::span<const uint8_t>()).ok());
  ASSERT_TRUE((*bus)->Handle(std::chrono::seconds(1)));
  EXPECT_EQ(delivered, 1);
  EXPECT_EQ(size, 0u);
}

// LCM 1.3.1's lcm_destroy never freed the mutex lcm_handle allocates (56 bytes per bus that
// ever handled a message: one per client session); far's LCM patch frees it. Found by
// LeakSanitizer in the daemon_datagram fuzz target; without the fix this test fails where leaks
// are detected (the ci-asan build, docs/testing.md).
TEST(LcmBusTest, ABusThatHandledMessagesLeavesNothingBehind) {
  for (int i = 0; i < 3; ++i) {
    auto bus = LcmBus::Create("memq://");
    ASSERT_TRUE(bus.ok()) << ToString(bus.error());
    int delivered = 0;
    (*bus)->Subscribe("FAR_TEST", [&](std::string_view, std::span<const uint8_t>) { ++delivered; });
    const uint8_t byte = 1;
    ASSERT_TRUE((*bus)->Publish("FAR_TEST", std::span<const uint8_t>(&byte, 1)).ok());
    ASSERT_TRUE((*bus)->Handle(std::chrono::seconds(1)));
    EXPECT_EQ(delivered, 1);
  }
}

}  // namespace
}  // namespace far::protocol
