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

}  // namespace
}  // namespace far::protocol
