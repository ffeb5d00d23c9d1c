// SocketServer (server/src/socket_server.cc) in process, as Daemon runs it: a real listening
// socket in a private directory, its own thread, session workers without GL.

#include "socket_server.h"

#include <stdlib.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "daemon_config.h"
#include "daemon_stats.h"
#include "replier.h"
#include "session_registry.h"
#include "session_worker.h"
#include "status_reply.h"
#include <gtest/gtest.h>

#include "far/model/scene_budget.h"
#include "far/protocol/convert.h"
#include "far/protocol/lcm_bus.h"
#include "far/protocol/local_socket.h"
#include "far/protocol/message.h"

namespace far::server {
namespace {

namespace wire = far_lcm;
using namespace std::chrono_literals;

class SocketServerTest : public ::testing::Test {
 protected:
  SocketServerTest() {
    char path[] = "/tmp/far-socket-server-test-XXXXXX";
    EXPECT_NE(mkdtemp(path), nullptr);
    dir_ = path;
    config_.socket_path = dir_ + "/far.sock";
    config_.lcm_url = "memq://";
    config_.max_opens_per_second_per_user = 1e9;
    config_.max_sessions_per_user = 64;
    config_.max_sessions = 64;
    auto bus = protocol::LcmBus::Create(config_.lcm_url);
    EXPECT_TRUE(bus.ok());
    bus_ = std::move(*bus);
    sessions_ = std::make_unique<SessionRegistry>(config_, budget_);
    replier_ = std::make_unique<Replier>(*bus_, stats_);
    // Aggregates, brace-initialized (clang does not build them from parentheses).
    workers_.reset(
        new WorkerContext{config_, *replier_, stats_, budget_, setup_allowance_, /*use_gl=*/false,
                          [this](int64_t id, const std::string&) { sessions_->Close(id); }});
    status_.reset(new StatusSources{config_,
                                    stats_,
                                    *sessions_,
                                    budget_,
                                    "none",
                                    "none",
                                    {"7"},
                                    std::chrono::steady_clock::now()});
    auto listener = protocol::LocalListener::Listen(SocketPathOf(config_));
    EXPECT_TRUE(listener.ok());
    server_ = std::make_unique<SocketServer>(std::move(*listener), config_, *sessions_, stats_,
                                             *workers_, *status_);
    thread_ = std::thread([this] { server_->Run(stop_); });
  }
  ~SocketServerTest() override {
    stop_ = true;
    thread_.join();
    sessions_->CloseAll();
    sessions_->ReapWorkers(/*wait=*/true);
    server_.reset();
    std::filesystem::remove_all(dir_);
  }

  // Sends an open on `connection` and returns whether the daemon accepted it.
  static bool Open(protocol::LocalConnection& connection, const std::string& name) {
    wire::open_session_t open{};
    open.protocol_version = protocol::kProtocolVersion;
    open.request_id = 7;
    open.client_name = name;
    auto bytes = protocol::EncodeMessage(open);
    if (!bytes || !connection.Send(*bytes).ok()) return false;
    auto answer = connection.Receive(protocol::kMaxStatusReplyBytes, 5s, /*accept_fd=*/true);
    if (!answer) return false;
    if (answer->fd >= 0) close(answer->fd);
    auto reply = protocol::DecodeMessage<wire::open_session_reply_t>(
        answer->bytes.data(), answer->bytes.size(), protocol::kMaxControlMessageBytes);
    return reply && reply->status == protocol::kWireOk;
  }

  std::string socket_path() const { return SocketPathOf(config_); }

  std::string dir_;
  DaemonConfig config_;
  std::unique_ptr<protocol::LcmBus> bus_;
  DaemonStats stats_;
  SharedSceneBudget budget_{BudgetTotalsOf(config_)};  // (totals as config_ has them so far)
  std::unique_ptr<SessionRegistry> sessions_;
  SetupAllowance setup_allowance_{config_.setup_allowance_ms};
  std::unique_ptr<Replier> replier_;
  std::unique_ptr<WorkerContext> workers_;
  std::unique_ptr<StatusSources> status_;
  std::atomic<bool> stop_{false};
  std::unique_ptr<SocketServer> server_;
  std::thread thread_;
};

// A client that connects while another session's client hangs up, and sends its open a moment
// later, is answered. The server once took the hang-up, in the same turn of its loop, for the
// new connection's first message: it read nothing there and dropped the new connection.
TEST_F(SocketServerTest, AConnectionAcceptedBesideAHangUpWaitsForItsMessage) {
  int answered = 0;
  constexpr int kRounds = 20;
  for (int round = 0; round < kRounds; ++round) {
    auto first = protocol::LocalConnection::Connect(socket_path());
    ASSERT_TRUE(first.ok());
    ASSERT_TRUE(Open(*first, "first"));
    auto second = protocol::LocalConnection::Connect(socket_path());
    ASSERT_TRUE(second.ok());
    first = protocol::LocalConnection(-1);  // hangs up: the daemon closes that session
    std::this_thread::sleep_for(20ms);      // the second client says nothing yet
    if (Open(*second, "second")) ++answered;
  }
  EXPECT_EQ(answered, kRounds);
}

// A session the shutdown closed and reaped before the socket thread started its worker gets
// none. It once got one: the thread outlived the registry, held the last reference, and
// destroyed its own joinable std::thread (std::terminate).
TEST_F(SocketServerTest, ASessionClosedBeforeItsWorkerStartsGetsNone) {
  protocol::OpenSessionParams params;
  params.client_name = "late";
  auto session = sessions_->Open(params, protocol::PeerCredentials{getpid(), getuid(), getgid()});
  ASSERT_TRUE(session.ok()) << far::ToString(session.error());
  ASSERT_EQ(sessions_->CloseAll().size(), 1u);
  EXPECT_EQ(sessions_->ReapWorkers(/*wait=*/true), 1);
  StartSessionWorker(*session, *workers_);
  EXPECT_FALSE((*session)->worker.joinable());
  EXPECT_TRUE((*session)->worker_done);
}

}  // namespace
}  // namespace far::server
