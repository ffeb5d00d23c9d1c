// Fuzz target open_reply: the client's side of the daemon's local socket, as far::Client and
// far-client run it (client/src/daemon_connection.cc): OpenSession (open_session_reply_t
// decoding, the request_id echo, the status, the segment's descriptor and ShmSegment::Open's
// checks of the segment behind it) and RequestStatus (status_reply_t decoding). The harness
// plays the daemon on the other end of a socket pair: it reads the client's request and sends
// the input's answer with the input's descriptor.
//
// Input: uint8 flags, then
//   flags bit 0: ask for status (RequestStatus); clear, open a session (OpenSession);
//         bit 1: the harness writes the request's request_id into the answer's bytes 12..19
//                (where both replies carry it), as an honest daemon echoes it;
//         bits 2-3: the descriptor sent with the answer: 0 none; 1 a daemon's segment
//                (ShmSegment::Create for the answer's session_id when it decodes, else 1);
//                2 a memory file the input fills: uint8 size choice (% 4: the size of a
//                segment with 64 KiB rings, that + 4096, 4096, 0), uint16 length and that many
//                bytes written at its start (its header), sealed against resizing when bit 4
//                is set; 3 a pipe's read end;
//   then the answer's bytes (the rest).
//
// Oracles besides the sanitizers: an open succeeds only with status ok, the echoed request_id
// and a segment of the answer's session; an honest answer (echoed, decoding, status ok, a
// daemon's segment) always succeeds, as does an echoed status reply that decodes; and the
// client leaves no descriptor open (a refused answer's descriptor is closed).

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "daemon_connection.h"
#include "fuzz_input.h"

#include "far/protocol/convert.h"
#include "far/protocol/local_socket.h"
#include "far/protocol/message.h"
#include "far/protocol/ring_layout.h"
#include "far/protocol/shm_segment.h"

namespace far::fuzz {
namespace {

namespace wire = far_lcm;
constexpr size_t kRequestIdOffset = 8 + 4;  // fingerprint, protocol_version

// What the harness's daemon sends: the answer, and a descriptor made from the input.
struct Answer {
  bool status = false;
  bool echo = false;
  uint8_t fd_kind = 0;
  uint8_t size_choice = 0;
  bool seal = false;
  std::vector<uint8_t> header;
  std::vector<uint8_t> bytes;
};

Answer ParseInput(FuzzInput& in) {
  Answer answer;
  const uint8_t flags = in.Take<uint8_t>();
  answer.status = flags & 1;
  answer.echo = flags & 2;
  answer.fd_kind = (flags >> 2) & 3;
  answer.seal = flags & 16;
  if (answer.fd_kind == 2) {
    answer.size_choice = in.Take<uint8_t>() % 4;
    const auto header = in.TakeBytes(in.Take<uint16_t>());
    answer.header.assign(header.begin(), header.end());
  }
  const auto rest = in.TakeBytes(in.left());
  answer.bytes.assign(rest.begin(), rest.end());
  return answer;
}

int64_t SessionIdOf(const std::vector<uint8_t>& bytes) {
  auto reply = protocol::DecodeMessageAnyVersion<wire::open_session_reply_t>(
      bytes.data(), bytes.size(), protocol::kMaxControlMessageBytes);
  return reply && reply->session_id > 0 ? reply->session_id : 1;
}

int MemoryFile(const Answer& answer) {
  const uint64_t segment =
      protocol::MakeSegmentLayout(protocol::kMinRingCapacity, protocol::kMinRingCapacity)
          .segment_size;
  const uint64_t sizes[] = {segment, segment + 4096, 4096, 0};
  const int fd = memfd_create("far-fuzz", MFD_CLOEXEC | MFD_ALLOW_SEALING);
  FAR_FUZZ_CHECK(fd >= 0);
  const uint64_t size = sizes[answer.size_choice];
  FAR_FUZZ_CHECK(ftruncate(fd, static_cast<off_t>(size)) == 0);
  const size_t length = std::min<size_t>(answer.header.size(), size);
  FAR_FUZZ_CHECK(pwrite(fd, answer.header.data(), length, 0) == static_cast<ssize_t>(length));
  if (answer.seal) FAR_FUZZ_CHECK(fcntl(fd, F_ADD_SEALS, F_SEAL_SHRINK | F_SEAL_GROW) == 0);
  return fd;
}

// The descriptor to send, and what must be kept alive until it is sent.
int DescriptorFor(const Answer& answer, const std::vector<uint8_t>& bytes,
                  std::unique_ptr<protocol::ShmSegment>* segment) {
  switch (answer.fd_kind) {
    case 1: {
      auto created =
          protocol::ShmSegment::Create(static_cast<uint64_t>(SessionIdOf(bytes)),
                                       {protocol::kMinRingCapacity, protocol::kMinRingCapacity});
      FAR_FUZZ_CHECK(created);
      *segment = std::move(*created);
      return (*segment)->fd();
    }
    case 2:
      return MemoryFile(answer);
    case 3: {
      int fds[2];
      FAR_FUZZ_CHECK(pipe2(fds, O_CLOEXEC) == 0);
      close(fds[1]);
      return fds[0];
    }
    default:
      return -1;
  }
}

// The daemon's end: reads the request, answers it, hangs up. Returns the bytes it sent. The
// daemon's segment, when it sent one, goes to *segment: like a real daemon's, it must live as
// long as the session (its destructor frees the memory, ShmSegment::Release).
std::vector<uint8_t> PlayDaemon(protocol::LocalConnection daemon, const Answer& answer,
                                std::unique_ptr<protocol::ShmSegment>* segment) {
  auto request = daemon.Receive(protocol::kMaxControlMessageBytes, std::chrono::seconds(10));
  FAR_FUZZ_CHECK(request);
  std::vector<uint8_t> bytes = answer.bytes;
  if (answer.echo && bytes.size() >= kRequestIdOffset + 8) {
    std::memcpy(bytes.data() + kRequestIdOffset, request->bytes.data() + kRequestIdOffset, 8);
  }
  const int fd = DescriptorFor(answer, bytes, segment);
  (void)daemon.Send(bytes, fd);
  if (fd >= 0 && answer.fd_kind != 1) close(fd);
  return bytes;
}

// An answer an honest daemon could have sent, which the client must accept.
bool Honest(const Answer& answer, const std::vector<uint8_t>& sent) {
  if (!answer.echo) return false;
  if (answer.status) {
    return answer.fd_kind == 0 && protocol::DecodeMessage<wire::status_reply_t>(
                                      sent.data(), sent.size(), protocol::kMaxStatusReplyBytes);
  }
  auto reply = protocol::DecodeMessage<wire::open_session_reply_t>(
      sent.data(), sent.size(), protocol::kMaxControlMessageBytes);
  return answer.fd_kind == 1 && reply && reply->status == protocol::kWireOk &&
         reply->session_id > 0;
}

void Run(const Answer& answer) {
  int pair[2];
  FAR_FUZZ_CHECK(socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, pair) == 0);
  protocol::LocalConnection client(pair[0]);
  std::vector<uint8_t> sent;
  std::unique_ptr<protocol::ShmSegment> segment;  // the session's, freed once the client is done
  std::thread daemon([&, end = protocol::LocalConnection(pair[1])]() mutable {
    sent = PlayDaemon(std::move(end), answer, &segment);
  });
  const client::ClientOptions options;
  bool ok = false;
  std::string refusal;  // why the client refused the answer (printed when it was honest)
  if (answer.status) {
    auto status = client::internal::RequestStatus(client, options);
    ok = status.ok();
    if (!status) refusal = far::ToString(status.error());
  } else {
    auto opened = client::internal::OpenSession(client, options);
    ok = opened.ok();
    if (!opened) refusal = far::ToString(opened.error());
    if (opened) {
      FAR_FUZZ_CHECK(opened->reply.status == protocol::kWireOk && opened->segment);
      FAR_FUZZ_CHECK(opened->segment->session_id() ==
                     static_cast<uint64_t>(opened->reply.session_id));
    }
  }
  daemon.join();
  if (Honest(answer, sent) && !ok)
    std::fprintf(stderr, "honest answer refused: %s\n", refusal.c_str());
  if (Honest(answer, sent)) FAR_FUZZ_CHECK(ok);
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far::fuzz;
  const int descriptors = OpenDescriptors();
  FuzzInput in(data, size);
  Run(ParseInput(in));
  FAR_FUZZ_CHECK(OpenDescriptors() == descriptors);
  return 0;
}
