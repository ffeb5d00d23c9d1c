// The daemon's local socket: messages with descriptors, peer credentials, a name that only one
// daemon can hold, and the client's trust check of where the socket is.
#include "far/protocol/local_socket.h"

#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace far::protocol {
namespace {

namespace fs = std::filesystem;

// A fresh directory for this test's socket, owner-only.
std::string TempDirectory() {
  std::string pattern = (fs::temp_directory_path() / "far-socket-test-XXXXXX").string();
  EXPECT_NE(mkdtemp(pattern.data()), nullptr);
  return pattern;
}

// Descriptors open in this process.
size_t OpenDescriptors() {
  size_t count = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator("/proc/self/fd")) ++count;
  return count;
}

// A connected pair: the listener's side and the client's.
struct Pair {
  std::unique_ptr<LocalListener> listener;
  std::optional<LocalConnection> client, server;
};

Pair Connect(const std::string& path) {
  Pair pair;
  auto listener = LocalListener::Listen(path);
  EXPECT_TRUE(listener) << listener.error().message;
  pair.listener = std::move(*listener);
  auto client = LocalConnection::Connect(path);
  EXPECT_TRUE(client) << client.error().message;
  pair.client.emplace(std::move(*client));
  for (int i = 0; i < 100 && !pair.server; ++i) {
    if (auto accepted = pair.listener->Accept()) pair.server.emplace(std::move(*accepted));
    usleep(1000);
  }
  EXPECT_TRUE(pair.server);
  return pair;
}

TEST(LocalSocketTest, CarriesMessagesDescriptorsAndTheKernelsWordOnWhoIsTalking) {
  const std::string dir = TempDirectory();
  Pair pair = Connect(dir + "/far.sock");
  ASSERT_TRUE(pair.client && pair.server);
  EXPECT_EQ(pair.server->peer().uid, geteuid());
  EXPECT_EQ(pair.server->peer().pid, getpid());
  // Any local user may connect: the daemon's limits are per user.
  struct stat info {};
  ASSERT_EQ(stat((dir + "/far.sock").c_str(), &info), 0);
  EXPECT_EQ(info.st_mode & 0777, 0666u);

  const int memfd = memfd_create("test", MFD_CLOEXEC);
  ASSERT_GE(memfd, 0);
  ASSERT_EQ(ftruncate(memfd, 1234), 0);
  const std::vector<uint8_t> hello = {1, 2, 3};
  ASSERT_TRUE(pair.server->Send(hello, memfd));
  close(memfd);
  auto received = pair.client->Receive(16, std::chrono::milliseconds(1000), true);
  ASSERT_TRUE(received) << received.error().message;
  EXPECT_EQ(received->bytes, hello);
  ASSERT_GE(received->fd, 0);
  ASSERT_EQ(fstat(received->fd, &info), 0);
  EXPECT_EQ(info.st_size, 1234);
  close(received->fd);
  fs::remove_all(dir);
}

TEST(LocalSocketTest, UnwantedDescriptorsAreClosedAndLongMessagesRefused) {
  const std::string dir = TempDirectory();
  Pair pair = Connect(dir + "/far.sock");
  ASSERT_TRUE(pair.client && pair.server);
  const int memfd = memfd_create("unwanted", MFD_CLOEXEC);
  ASSERT_GE(memfd, 0);
  ASSERT_TRUE(pair.client->Send(std::vector<uint8_t>{9}, memfd));
  close(memfd);
  const size_t before = OpenDescriptors();
  // The daemon never takes a client's descriptor: it is closed on arrival.
  auto received = pair.server->Receive(16, std::chrono::milliseconds(1000), false);
  ASSERT_TRUE(received);
  EXPECT_EQ(received->fd, -1);
  EXPECT_EQ(OpenDescriptors(), before);  // nothing of it is left open in this process
  ASSERT_TRUE(pair.client->Send(std::vector<uint8_t>(100, 7)));
  auto large = pair.server->Receive(16, std::chrono::milliseconds(1000), false);
  ASSERT_FALSE(large);
  EXPECT_EQ(large.error().code, ErrorCode::kLimitExceeded);
  auto nothing = pair.server->Receive(16, std::chrono::milliseconds(10), false);
  EXPECT_EQ(nothing.error().code, ErrorCode::kTimeout);
  EXPECT_FALSE(pair.server->PeerClosed());
  pair.client.reset();
  EXPECT_TRUE(pair.server->PeerClosed());
  auto gone = pair.server->Receive(16, std::chrono::milliseconds(1000), false);
  EXPECT_EQ(gone.error().code, ErrorCode::kUnavailable);
  fs::remove_all(dir);
}

TEST(LocalSocketTest, ANameIsHeldByOneDaemonAndFreedWhenItDies) {
  const std::string dir = TempDirectory();
  const std::string path = dir + "/far.sock";
  {
    auto first = LocalListener::Listen(path);
    ASSERT_TRUE(first);
    auto second = LocalListener::Listen(path);
    ASSERT_FALSE(second);
    EXPECT_NE(second.error().message.find("another far-daemon is listening"), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(path));  // removed with its listener
  // A socket left by a daemon that died (nobody listens) is taken over.
  {
    const int fd = socket(AF_UNIX, SOCK_SEQPACKET, 0);
    sockaddr_un address{};
    address.sun_family = AF_UNIX;
    std::snprintf(address.sun_path, sizeof(address.sun_path), "%s", path.c_str());
    ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0);
    close(fd);
  }
  ASSERT_TRUE(fs::exists(path));
  EXPECT_TRUE(LocalListener::Listen(path));
  fs::remove_all(dir);
}

TEST(LocalSocketTest, NobodyCanPutASocketWhereAClientLooks) {
  const std::string dir = TempDirectory();
  // A directory others may write to: the daemon refuses it, and so does a client.
  ASSERT_EQ(chmod(dir.c_str(), 0777), 0);
  auto listener = LocalListener::Listen(dir + "/far.sock");
  ASSERT_FALSE(listener);
  EXPECT_EQ(listener.error().code, ErrorCode::kPermissionDenied);
  ASSERT_EQ(chmod(dir.c_str(), 0755), 0);
  auto good = LocalListener::Listen(dir + "/far.sock");
  ASSERT_TRUE(good);
  ASSERT_EQ(chmod(dir.c_str(), 0777), 0);  // someone loosened it since
  auto client = LocalConnection::Connect(dir + "/far.sock");
  ASSERT_FALSE(client);
  EXPECT_EQ(client.error().code, ErrorCode::kPermissionDenied);
  EXPECT_NE(client.error().message.find("may be written by other users"), std::string::npos);
  ASSERT_EQ(chmod(dir.c_str(), 0700), 0);
  // The daemon's identity must match the socket's owner.
  PeerCredentials other;
  other.uid = geteuid() + 4242;
  auto impostor = CheckDaemonSocket(dir + "/far.sock", other);
  ASSERT_FALSE(impostor);
  EXPECT_NE(impostor.error().message.find("listens on it"), std::string::npos);
  fs::remove_all(dir);
}

// Out of descriptors (EMFILE), accept fails and the connection stays in the backlog, so the
// listener stays readable and a daemon that polls it spins (half a core, issue 41). The
// listener closes one waiting connection unanswered with its reserve descriptor instead: its
// client hears at once, and the listener is quiet again.
TEST(LocalSocketTest, OutOfDescriptorsAcceptClosesOneWaitingConnectionAndRecovers) {
  const std::string dir = TempDirectory();
  auto listener = LocalListener::Listen(dir + "/far.sock");
  ASSERT_TRUE(listener) << listener.error().message;
  auto client = LocalConnection::Connect(dir + "/far.sock");
  ASSERT_TRUE(client) << client.error().message;
  // This process's descriptors, all taken (RLIMIT_NOFILE lowered to what is open, plus a few).
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_NOFILE, &old), 0);
  rlimit low = old;
  low.rlim_cur = OpenDescriptors() + 8;
  ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &low), 0);
  std::vector<int> fillers;
  for (int fd; (fd = open("/dev/null", O_RDONLY | O_CLOEXEC)) >= 0;) fillers.push_back(fd);
  const int full_errno = errno;

  const std::optional<LocalConnection> refused = (*listener)->Accept();
  const bool out = (*listener)->out_of_descriptors();
  for (const int fd : fillers) close(fd);
  ASSERT_EQ(setrlimit(RLIMIT_NOFILE, &old), 0);
  ASSERT_EQ(full_errno, EMFILE);
  EXPECT_FALSE(refused.has_value());
  EXPECT_TRUE(out);
  // The waiting connection was closed: its client hears it, and nothing is left to accept.
  auto heard = client->Receive(16, std::chrono::seconds(2));
  ASSERT_FALSE(heard);
  EXPECT_EQ(heard.error().code, ErrorCode::kUnavailable) << heard.error().message;
  EXPECT_FALSE((*listener)->Accept().has_value());
  EXPECT_FALSE((*listener)->out_of_descriptors());
  // With descriptors again, the next client is accepted.
  auto next = LocalConnection::Connect(dir + "/far.sock");
  ASSERT_TRUE(next) << next.error().message;
  std::optional<LocalConnection> accepted;
  for (int i = 0; i < 100 && !accepted; ++i) {
    accepted = (*listener)->Accept();
    if (!accepted) usleep(1000);
  }
  EXPECT_TRUE(accepted.has_value());
  fs::remove_all(dir);
}

TEST(LocalSocketTest, NoDaemonIsNotFound) {
  auto client = LocalConnection::Connect("/nonexistent-far-dir/far.sock");
  ASSERT_FALSE(client);
  EXPECT_EQ(client.error().code, ErrorCode::kNotFound);
  auto too_long = LocalConnection::Connect("/" + std::string(200, 'a'));
  ASSERT_FALSE(too_long);
  EXPECT_EQ(too_long.error().code, ErrorCode::kInvalidArgument);
}

// A signal that interrupts a wait (poll's EINTR) is not the peer going away: the wait goes on.
// Found while fuzzing: libFuzzer's timeout alarm interrupted the waits of the socket_handshake
// and open_reply targets, and Receive said "poll failed" (kUnavailable), as if the peer had
// closed the connection; a daemon dropped a client in its handshake that way, and a client with
// timers of its own could fail to open its session.
TEST(LocalSocketTest, ASignalDuringAWaitDoesNotEndIt) {
  struct sigaction ignore {};
  ignore.sa_handler = [](int) {};  // no SA_RESTART (poll is never restarted anyway)
  struct sigaction old {};
  ASSERT_EQ(sigaction(SIGUSR1, &ignore, &old), 0);
  const std::string dir = TempDirectory();
  Pair pair = Connect(dir + "/far.sock");
  ASSERT_TRUE(pair.client && pair.server);
  const pthread_t waiter = pthread_self();
  std::thread interrupter([&] {
    for (int i = 0; i < 20; ++i) {
      pthread_kill(waiter, SIGUSR1);
      usleep(5000);
    }
    const std::vector<uint8_t> late = {7};
    EXPECT_TRUE(pair.server->Send(late));
  });
  auto received = pair.client->Receive(16, std::chrono::seconds(10));
  interrupter.join();
  sigaction(SIGUSR1, &old, nullptr);
  ASSERT_TRUE(received) << received.error().message;
  EXPECT_EQ(received->bytes, std::vector<uint8_t>{7});
  fs::remove_all(dir);
}

}  // namespace
}  // namespace far::protocol
