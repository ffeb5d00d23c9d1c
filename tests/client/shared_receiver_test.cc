// The receiving thread a process's Clients share on one LCM URL (client/src/shared_receiver.h):
// one per URL while it has holders, each listener passed only its own channel's messages and
// ticked, and a listener detached is never called again (Detach waits for a call in progress,
// so that a Client can free what its callbacks use). Over udpm, in the private network namespace
// this test runs in (deploy/netns-run.sh); the LCM subscriptions the receiver makes and ends
// while its thread handles are tested first, on an LcmBus alone.

#include "shared_receiver.h"

#include <atomic>
#include <chrono>
#include <future>
#include <string>
#include <thread>

#include <gtest/gtest.h>

#include "far/protocol/channels.h"

namespace far::client::internal {
namespace {

using std::chrono::milliseconds;

const std::string kUrl(protocol::kDefaultLcmUrl);

// Waits up to 2 s for `done()`.
template <typename Done>
bool WaitFor(Done done) {
  for (int i = 0; i < 200 && !done(); ++i) std::this_thread::sleep_for(milliseconds(10));
  return done();
}

void Send(SharedReceiver& receiver, const std::string& channel) {
  const uint8_t byte = 7;
  ASSERT_TRUE(receiver.Publish(channel, std::span<const uint8_t>(&byte, 1)).ok());
}

// A subscription ended is never called again, and one made while another thread handles
// messages gets them from then on (the client's shared receiver subscribes each session's
// reply channel while its thread handles the others').
TEST(LcmBusThreadsTest, SubscribeAndUnsubscribeWhileAnotherThreadHandles) {
  auto bus = protocol::LcmBus::Create(kUrl);
  ASSERT_TRUE(bus.ok()) << ToString(bus.error());
  // Before the handling thread, as SharedReceiver does: udpm makes its sockets and their
  // mutexes on the first subscribe or handle, which is not safe from two threads at once.
  (*bus)->Handle(std::chrono::milliseconds(0));
  std::atomic<bool> stop{false};
  std::thread handler([&] {
    while (!stop) (*bus)->Handle(std::chrono::milliseconds(5));
  });
  std::atomic<int> a{0}, b{0};
  const auto id_a =
      (*bus)->Subscribe("FAR_A", [&](std::string_view, std::span<const uint8_t>) { ++a; });
  (*bus)->Subscribe("FAR_B", [&](std::string_view, std::span<const uint8_t>) { ++b; });
  const uint8_t byte = 1;
  auto publish = [&](const char* channel) {
    ASSERT_TRUE((*bus)->Publish(channel, std::span<const uint8_t>(&byte, 1)).ok());
  };
  auto wait_for = [](const std::atomic<int>& count, int value) {
    for (int i = 0; i < 200 && count < value; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return count.load();
  };
  publish("FAR_A");
  publish("FAR_B");
  EXPECT_EQ(wait_for(a, 1), 1);
  EXPECT_EQ(wait_for(b, 1), 1);
  (*bus)->Unsubscribe(id_a);
  (*bus)->Unsubscribe(id_a);  // twice: ignored
  publish("FAR_A");
  publish("FAR_B");
  EXPECT_EQ(wait_for(b, 2), 2);  // B's second came, so A's had been handled (one queue)
  EXPECT_EQ(a, 1);
  stop = true;
  handler.join();
}

TEST(SharedReceiverTest, OneReceiverPerUrlWhileItHasHolders) {
  auto first = SharedReceiver::For(kUrl);
  auto second = SharedReceiver::For(kUrl);
  ASSERT_TRUE(first.ok()) << ToString(first.error());
  ASSERT_TRUE(second.ok()) << ToString(second.error());
  EXPECT_EQ(first->get(), second->get());
  EXPECT_FALSE((*first)->OnReceivingThread());
}

TEST(SharedReceiverTest, EachListenerGetsOnlyItsOwnChannelAndEveryTick) {
  auto receiver = SharedReceiver::For(kUrl);
  ASSERT_TRUE(receiver.ok()) << ToString(receiver.error());
  std::atomic<int> a{0}, b{0}, ticks_a{0}, ticks_b{0};
  std::atomic<bool> on_receiving_thread{true};
  const auto id_a = (*receiver)->Attach("FAR_S1_REPLY", {[&](std::span<const uint8_t>) {
                                                           on_receiving_thread =
                                                               on_receiving_thread &&
                                                               (*receiver)->OnReceivingThread();
                                                           ++a;
                                                         },
                                                         [&] { ++ticks_a; }});
  const auto id_b = (*receiver)->Attach(
      "FAR_S2_REPLY", {[&](std::span<const uint8_t>) { ++b; }, [&] { ++ticks_b; }});
  Send(**receiver, "FAR_S1_REPLY");
  Send(**receiver, "FAR_S1_REPLY");
  Send(**receiver, "FAR_S3_REPLY");  // nobody's
  Send(**receiver, "FAR_S2_REPLY");
  EXPECT_TRUE(WaitFor([&] { return a == 2 && b == 1; })) << a << " " << b;
  EXPECT_TRUE(on_receiving_thread);
  EXPECT_TRUE(WaitFor([&] { return ticks_a >= 2 && ticks_b >= 2; }));
  (*receiver)->Detach(id_a);
  (*receiver)->Detach(id_b);
  EXPECT_EQ(a, 2);
  EXPECT_EQ(b, 1);
}

// A Client frees what its callbacks use once Detach returns: a callback running then must have
// finished, and no later message reaches it.
TEST(SharedReceiverTest, DetachWaitsForTheCallbackInProgressAndNoneComesAfter) {
  auto receiver = SharedReceiver::For(kUrl);
  ASSERT_TRUE(receiver.ok()) << ToString(receiver.error());
  std::promise<void> entered, release;
  auto released = release.get_future().share();
  std::atomic<int> calls{0};
  std::atomic<bool> in_callback{false};
  const auto id = (*receiver)->Attach("FAR_S4_REPLY", {[&](std::span<const uint8_t>) {
                                                         in_callback = true;
                                                         if (++calls == 1) {
                                                           entered.set_value();
                                                           released.wait();
                                                         }
                                                         in_callback = false;
                                                       },
                                                       [] {}});
  Send(**receiver, "FAR_S4_REPLY");
  ASSERT_EQ(entered.get_future().wait_for(std::chrono::seconds(2)), std::future_status::ready);
  Send(**receiver, "FAR_S4_REPLY");  // queued behind the call in progress
  auto detached = std::async(std::launch::async, [&] {
    (*receiver)->Detach(id);
    return in_callback.load();
  });
  EXPECT_EQ(detached.wait_for(milliseconds(200)), std::future_status::timeout);
  release.set_value();
  EXPECT_FALSE(detached.get());  // the callback had returned when Detach did
  std::this_thread::sleep_for(milliseconds(100));
  EXPECT_EQ(calls, 1);  // the queued message found no listener
}

// A callback may detach its own listener (a session that ends while it handles a message):
// Detach must not wait for the call it is part of.
TEST(SharedReceiverTest, ACallbackMayDetachItsOwnListener) {
  auto receiver = SharedReceiver::For(kUrl);
  ASSERT_TRUE(receiver.ok()) << ToString(receiver.error());
  std::atomic<SharedReceiver::ListenerId> id{0};
  std::atomic<int> calls{0};
  id = (*receiver)->Attach("FAR_S5_REPLY", {[&](std::span<const uint8_t>) {
                                              ++calls;
                                              (*receiver)->Detach(id);
                                            },
                                            [] {}});
  Send(**receiver, "FAR_S5_REPLY");
  EXPECT_TRUE(WaitFor([&] { return calls == 1; }));
  Send(**receiver, "FAR_S5_REPLY");
  std::this_thread::sleep_for(milliseconds(100));
  EXPECT_EQ(calls, 1);
}

}  // namespace
}  // namespace far::client::internal
