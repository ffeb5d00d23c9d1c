// Writes the generated part of the fuzz targets' seed corpora (tests/fuzz/make_corpus.sh copies
// the rest from tests/data): encoded sample messages (the protocol tests' samples), sealed
// replies, datagram sequences of whole sessions, local socket handshakes and the daemon's
// answers to them, update-ring sessions and records written by the client's UpdateWriter, and
// binary PLY and STL files. Inputs of the structured targets follow the layouts at the top of
// their <target>_fuzzer.cc.
//
//   far_fuzz_make_seeds <output folder>   # writes <output folder>/<target>/<seed>

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "protocol/test_messages.h"
#include "protocol/test_ring.h"
#include "sealed_session.h"

#include "far/io/mesh_io.h"
#include "far/protocol/channels.h"
#include "far/protocol/convert.h"
#include "far/protocol/ring_records.h"
#include "far/protocol/session_auth.h"
#include "far/protocol/shm_reply.h"
#include "far/protocol/shm_segment.h"

namespace far::fuzz {
namespace {

namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;
using protocol::testing::TestRing;

fs::path g_out;

void Write(const std::string& target, const std::string& name, const Bytes& bytes) {
  fs::create_directories(g_out / target);
  std::ofstream(g_out / target / name, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

template <typename T>
void Put(Bytes& out, T value) {
  const auto* p = reinterpret_cast<const uint8_t*>(&value);
  out.insert(out.end(), p, p + sizeof(T));
}

template <typename T>
Bytes Encoded(const T& message) {
  auto bytes = protocol::EncodeMessage(message);
  if (!bytes) std::abort();
  return *bytes;
}

// ---- lcm_message ----------------------------------------------------------------------------

void LcmMessageSeeds() {
  namespace t = protocol::testing;
  Write("lcm_message", "open_session", Encoded(t::SampleOpenSession()));
  Write("lcm_message", "open_session_reply", Encoded(t::SampleOpenSessionReply()));
  Write("lcm_message", "sealed", Encoded(t::SampleSealed()));
  Write("lcm_message", "step_status", Encoded(t::SampleStepStatus()));
  Write("lcm_message", "step_request", Encoded(t::SampleStepRequest()));
  auto plain = t::SampleStepRequest();
  plain.method = "";
  plain.output = "contacts";
  plain.has_distance = false;
  plain.distance = 0;
  plain.timeout_ms = 0;
  Write("lcm_message", "step_request_default_method", Encoded(plain));
  Write("lcm_message", "step_reply", Encoded(t::SampleStepReply()));
  Write("lcm_message", "error", Encoded(t::SampleError()));
  Write("lcm_message", "status_request", Encoded(t::SampleStatusRequest()));
  Write("lcm_message", "status_reply", Encoded(t::SampleStatusReply()));
}

// ---- sealed_message -------------------------------------------------------------------------

// The stub of the sample step reply as the target's reply ring holds it (a fresh ring: the
// first record, at index 0).
far_lcm::step_reply_t SampleStub() {
  TestRing ring(protocol::kMinRingCapacity);
  protocol::RingWriter writer(ring.region());
  const auto full = protocol::testing::SampleStepReply();
  auto ref = protocol::WriteShmReply(writer, Encoded(full));
  if (!ref) std::abort();
  return protocol::MakeShmReplyStub(full, *ref);
}

// Mode 1 (the harness seals `inner`), with `flips` (offset, xor) applied to the sealed bytes.
Bytes HarnessSealed(const Bytes& inner, int64_t request_id,
                    const std::vector<std::pair<uint16_t, uint8_t>>& flips = {}) {
  Bytes out = {1};
  Put<int64_t>(out, request_id);
  Put<uint8_t>(out, static_cast<uint8_t>(flips.size()));
  for (const auto& [offset, mask] : flips) {
    Put<uint16_t>(out, offset);
    Put<uint8_t>(out, mask);
  }
  out.insert(out.end(), inner.begin(), inner.end());
  return out;
}

void SealedMessageSeeds() {
  namespace t = protocol::testing;
  auto session = [](auto message) {
    message.session_id = kSealedSessionId;
    return Encoded(message);
  };
  Write("sealed_message", "step_status", HarnessSealed(session(t::SampleStepStatus()), 1));
  Write("sealed_message", "error", HarnessSealed(session(t::SampleError()), 2));
  Write("sealed_message", "step_reply", HarnessSealed(session(t::SampleStepReply()), 3));
  Write("sealed_message", "step_reply_stub", HarnessSealed(session(SampleStub()), 4));
  Write("sealed_message", "altered_nonce",
        HarnessSealed(session(t::SampleStepStatus()), 5, {{30, 0x01}}));
  // A datagram as received (mode 0): sealed with the session's key by the daemon's SealEncoded.
  auto sealed =
      protocol::SealEncoded(session(t::SampleError()), kSealedSessionId, 6, SealedSessionKey());
  if (!sealed) std::abort();
  Bytes received = {0};
  received.insert(received.end(), sealed->begin(), sealed->end());
  Write("sealed_message", "received", received);
}

// ---- daemon_datagram ------------------------------------------------------------------------

enum Channel : uint8_t { kSession1 = 0, kSession2 = 1, kOtherDaemon = 4 };
enum DatagramFlags : uint8_t { kSign = 1, kTake = 2, kClose = 4 };

void PutDatagram(Bytes& out, uint8_t channel, uint8_t flags, const Bytes& payload) {
  Put<uint8_t>(out, channel);
  Put<uint8_t>(out, flags);
  Put<uint16_t>(out, static_cast<uint16_t>(payload.size()));
  out.insert(out.end(), payload.begin(), payload.end());
}

// A step request of session `session_id`.
Bytes Step(int64_t session_id, int64_t request_id, int resolution = 512) {
  auto message = protocol::testing::SampleStepRequest();
  message.session_id = session_id;
  message.request_id = request_id;
  message.step_id = request_id;
  message.resolution = resolution;
  return Encoded(message);
}

void DaemonDatagramSeeds() {
  Bytes steps;  // signed steps of both sessions, the workers taking them in between
  PutDatagram(steps, kSession1, kSign, Step(1, 1));
  PutDatagram(steps, kSession2, kSign, Step(2, 1));
  PutDatagram(steps, kSession1, kSign | kTake, Step(1, 2));
  PutDatagram(steps, kSession1, kSign, Step(1, 3, 4096));  // over max_resolution
  Write("daemon_datagram", "steps", steps);

  Bytes busy;  // more steps than the queue holds, then more than the request rate allows
  for (int i = 1; i <= 10; ++i) PutDatagram(busy, kSession1, kSign, Step(1, i));
  Write("daemon_datagram", "busy", busy);

  Bytes unsigned_step;  // a request without the key's tag, and one on another daemon's channel
  PutDatagram(unsigned_step, kSession1, 0, Step(1, 1));
  PutDatagram(unsigned_step, kOtherDaemon, kSign, Step(1, 2));
  Write("daemon_datagram", "unsigned_step", unsigned_step);

  Bytes replayed;  // the same signed request twice, then on the other session's channel
  PutDatagram(replayed, kSession1, kSign, Step(1, 5));
  PutDatagram(replayed, kSession1, kSign, Step(1, 5));
  PutDatagram(replayed, kSession2, kSign, Step(1, 6));
  Write("daemon_datagram", "replayed", replayed);

  Bytes closed;  // a session closed, then asked for a step
  PutDatagram(closed, kSession2, kSign | kClose, Step(2, 1));
  PutDatagram(closed, kSession2, kSign, Step(2, 2));
  Write("daemon_datagram", "closed", closed);

  Bytes other_version;  // a signed request of another protocol version
  auto old = protocol::testing::SampleStepRequest();
  old.session_id = 1;
  old.protocol_version = protocol::kProtocolVersion + 1;
  PutDatagram(other_version, kSession1, kSign, Encoded(old));
  Write("daemon_datagram", "other_version", other_version);
}

// ---- socket_handshake -----------------------------------------------------------------------

enum HandshakeFlags : uint8_t { kPassFd = 1, kSecondMessage = 2 };

Bytes Handshake(uint8_t flags, const Bytes& first, const Bytes& second = {}) {
  Bytes out = {flags};
  if (flags & kSecondMessage) Put<uint16_t>(out, static_cast<uint16_t>(first.size()));
  out.insert(out.end(), first.begin(), first.end());
  out.insert(out.end(), second.begin(), second.end());
  return out;
}

void SocketHandshakeSeeds() {
  namespace t = protocol::testing;
  auto open = t::SampleOpenSession();
  open.update_ring_bytes = 0;  // the daemon's sizes
  Write("socket_handshake", "open", Handshake(0, Encoded(open)));
  open.reply_ring_bytes = int64_t{128} << 10;
  Write("socket_handshake", "open_ring_sizes", Handshake(kPassFd, Encoded(open)));
  Write("socket_handshake", "open_then_more",
        Handshake(kSecondMessage, Encoded(open), Encoded(t::SampleStatusRequest())));
  Write("socket_handshake", "open_too_large_ring", Handshake(0, Encoded(t::SampleOpenSession())));
  auto old = t::SampleOpenSession();
  old.protocol_version = protocol::kProtocolVersion - 1;
  Write("socket_handshake", "open_other_version", Handshake(0, Encoded(old)));
  auto unnamed = t::SampleOpenSession();
  unnamed.client_name = "";
  Write("socket_handshake", "open_unnamed", Handshake(0, Encoded(unnamed)));
  Write("socket_handshake", "status", Handshake(0, Encoded(t::SampleStatusRequest())));
  Write("socket_handshake", "step_request", Handshake(kPassFd, Encoded(t::SampleStepRequest())));
}

// ---- open_reply -----------------------------------------------------------------------------

enum ReplyFlags : uint8_t {
  kStatus = 1,
  kEcho = 2,
  kSegmentFd = 1 << 2,
  kFileFd = 2 << 2,
  kPipeFd = 3 << 2,
  kSeal = 16
};

// The header of a daemon's segment for session `session_id` with 64 KiB rings.
Bytes SegmentHeader(uint64_t session_id) {
  auto segment = protocol::ShmSegment::Create(
      session_id, {protocol::kMinRingCapacity, protocol::kMinRingCapacity});
  if (!segment) std::abort();
  Bytes header(sizeof(protocol::SegmentHeader));
  if (pread((*segment)->fd(), header.data(), header.size(), 0) !=
      static_cast<ssize_t>(header.size()))
    std::abort();
  return header;
}

void OpenReplySeeds() {
  namespace t = protocol::testing;
  auto reply = t::SampleOpenSessionReply();
  reply.update_ring_bytes = reply.reply_ring_bytes = protocol::kMinRingCapacity;
  reply.shm_bytes = static_cast<int64_t>(
      protocol::MakeSegmentLayout(protocol::kMinRingCapacity, protocol::kMinRingCapacity)
          .segment_size);
  const Bytes accepted = Encoded(reply);
  auto with = [](uint8_t flags, const Bytes& bytes) {
    Bytes out = {flags};
    out.insert(out.end(), bytes.begin(), bytes.end());
    return out;
  };
  Write("open_reply", "accepted", with(kEcho | kSegmentFd, accepted));
  Write("open_reply", "accepted_no_segment", with(kEcho, accepted));
  Write("open_reply", "accepted_pipe", with(kEcho | kPipeFd, accepted));
  Write("open_reply", "another_request", with(kSegmentFd, accepted));
  Bytes file = {kEcho | kFileFd | kSeal, 0};
  const Bytes header = SegmentHeader(static_cast<uint64_t>(reply.session_id));
  Put<uint16_t>(file, static_cast<uint16_t>(header.size()));
  file.insert(file.end(), header.begin(), header.end());
  file.insert(file.end(), accepted.begin(), accepted.end());
  Write("open_reply", "accepted_file", file);
  auto refused = reply;
  refused.status = protocol::ToWireStatus(ErrorCode::kLimitExceeded);
  refused.status_name = "limit_exceeded";
  refused.message = "max_sessions: 64 sessions are open";
  Write("open_reply", "refused", with(kEcho | kSegmentFd, Encoded(refused)));
  Write("open_reply", "status", with(kStatus | kEcho, Encoded(t::SampleStatusReply())));
}

// ---- ring_reader ----------------------------------------------------------------------------

constexpr uint64_t kRingCapacity = protocol::kMinRingCapacity;

// Records the client writes, turned into ring_reader operations: each record's bytes poked at
// its ring offset, then the write index published and the records drained, as one step.
class RingSession {
 public:
  RingSession() : ring_(kRingCapacity), writer_(ring_.region()) {}
  protocol::UpdateWriter& writer() { return writer_; }

  // Pokes the records written since the last call (their non-zero bytes: the daemon's ring
  // starts zeroed), publishes and drains them.
  void Step() {
    const uint64_t end = ring_.write_index.load();
    for (uint64_t at = poked_; at < end;) {
      if (Byte(at) == 0) {
        ++at;
        continue;
      }
      uint64_t stop = at;  // up to the next run of 16 zeros
      for (uint64_t zeros = 0; stop < end && zeros < 16 && stop - at < 0xffff; ++stop) {
        zeros = Byte(stop) == 0 ? zeros + 1 : 0;
      }
      Put<uint8_t>(ops_, 0);
      Put<uint16_t>(ops_, static_cast<uint16_t>(at & (kRingCapacity - 1)));
      Put<uint16_t>(ops_, static_cast<uint16_t>(stop - at));
      for (uint64_t i = at; i < stop; ++i) ops_.push_back(Byte(i));
      at = stop;
    }
    poked_ = end;
    Put<uint8_t>(ops_, 1);
    Put<uint64_t>(ops_, end);
    Put<uint8_t>(ops_, 2);
    Put<uint64_t>(ops_, writer_.last_sequence());
    ring_.read_index = end;  // the daemon consumed them
  }
  // The daemon writes a step reply of `payload` after the client read up to `read_index`.
  void Reply(uint64_t read_index, const Bytes& payload) {
    Put<uint8_t>(ops_, 3);
    Put<uint64_t>(ops_, read_index);
    Put<uint16_t>(ops_, static_cast<uint16_t>(payload.size()));
    ops_.insert(ops_.end(), payload.begin(), payload.end());
  }
  const Bytes& ops() const { return ops_; }

 private:
  uint8_t Byte(uint64_t index) const { return ring_.data[index & (kRingCapacity - 1)]; }

  TestRing ring_;
  protocol::UpdateWriter writer_;
  uint64_t poked_ = 0;
  Bytes ops_;
};

Mesh Tetrahedron() {
  Mesh mesh;
  mesh.p_MV = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

void RingReaderSeeds() {
  const Mesh mesh = Tetrahedron();
  Pose moved;
  moved.translation = {0.5, 0, 0};
  moved.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  {
    RingSession s;  // every record type over two steps, and a reply
    (void)s.writer().AddObject(1, mesh, Motion::kStatic, Pose{});
    (void)s.writer().AddObject(2, mesh, Motion::kDeformable, moved);
    s.Step();
    (void)s.writer().SetPose(2, Pose{});
    std::vector<Eigen::Vector3d> bent = mesh.p_MV;
    bent[3].z() = 2;
    (void)s.writer().SetVertices(2, bent);
    (void)s.writer().RemoveObject(1);
    s.Step();
    s.Reply(0, Encoded(protocol::testing::SampleStepReply()));
    Write("ring_reader", "every_record", s.ops());
  }
  {
    // A large record of an unknown type (a content error: the daemon consumes it and reports
    // it), then records that wrap around the end of the ring.
    RingSession s;
    const Bytes filler(65000, 0);
    (void)s.writer().ring().Write(static_cast<protocol::RecordType>(99), {filler});
    s.Step();
    (void)s.writer().AddObject(8, mesh, Motion::kDeformable, moved);
    (void)s.writer().SetPose(8, Pose{});
    s.Step();
    Write("ring_reader", "wrap_around", s.ops());
  }
}

// ---- ring_record ----------------------------------------------------------------------------

// The record the client's writer makes with `write`, as the ring_record target reads it.
template <typename WriteFn>
void RecordSeed(const std::string& name, WriteFn write) {
  TestRing ring(kRingCapacity);
  protocol::UpdateWriter writer(ring.region());
  auto at = write(writer);
  if (!at) std::abort();
  Bytes out = {0};
  for (uint64_t i = 0; i < at->size; ++i) out.push_back(ring.data[at->index + i]);
  Write("ring_record", name, out);
}

void RingRecordSeeds() {
  const Mesh mesh = Tetrahedron();
  Pose moved;
  moved.translation = {0.5, 0, 0};
  moved.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  RecordSeed("add_object", [&](auto& w) { return w.AddObject(7, mesh, Motion::kRigid, moved); });
  RecordSeed("remove_object", [&](auto& w) { return w.RemoveObject(1); });
  RecordSeed("set_pose", [&](auto& w) { return w.SetPose(2, moved); });
  std::vector<Eigen::Vector3d> bent = mesh.p_MV;
  bent[3].z() = 2;
  RecordSeed("set_vertices", [&](auto& w) { return w.SetVertices(3, bent); });
}

// ---- mesh files -----------------------------------------------------------------------------

// Writes `mesh` with far's writer in the format of `name`'s extension, then copies it as a seed.
void MeshFileSeed(const std::string& target, const std::string& name, const Mesh& mesh) {
  const fs::path path = fs::temp_directory_path() / ("far-make-seeds-" + name);
  if (!WriteMesh(mesh, path).ok()) std::abort();
  std::ifstream in(path, std::ios::binary);
  Write(target, name, Bytes(std::istreambuf_iterator<char>(in), {}));
  fs::remove(path);
}

// A big-endian PLY with properties, lists and elements the reader must skip.
Bytes BigEndianPly() {
  std::string header =
      "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty float x\n"
      "property uchar red\nproperty float y\nproperty list uchar double extra\nproperty float z\n"
      "element edge 1\nproperty int vertex1\nproperty int vertex2\n"
      "element face 2\nproperty list int ushort vertex_indices\nproperty float quality\n"
      "end_header\n";
  Bytes out(header.begin(), header.end());
  auto big = [&](auto value) {
    uint8_t bytes[sizeof(value)];
    std::memcpy(bytes, &value, sizeof(value));
    for (size_t i = sizeof(value); i-- > 0;) out.push_back(bytes[i]);
  };
  const float corners[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const auto& c : corners) {
    big(c[0]);
    big(uint8_t{7});
    big(c[1]);
    big(uint8_t{1});
    big(2.5);
    big(0.0f);
  }
  big(int32_t{0});
  big(int32_t{1});
  for (const uint16_t third : {2, 3}) {
    big(int32_t{3});
    big(uint16_t{0});
    big(static_cast<uint16_t>(third - 1));
    big(third);
    big(0.5f);
  }
  return out;
}

void MeshSeeds() {
  const Mesh mesh = Tetrahedron();
  MeshFileSeed("obj_reader", "tetrahedron.obj", mesh);
  MeshFileSeed("ply_reader", "tetrahedron_binary_le.ply", mesh);
  Write("ply_reader", "square_binary_be_skips.ply", BigEndianPly());
  MeshFileSeed("stl_reader", "tetrahedron_binary.stl", mesh);
}

// ---- daemon_config --------------------------------------------------------------------------

// The typed-members form (daemon_config_fuzzer.cc) of a valid configuration; key indices are
// those of its kKeys.
void DaemonConfigSeeds() {
  Bytes out = {0xff};
  auto integer = [&](uint8_t key, int64_t value) {
    Put<uint8_t>(out, key);
    Put<uint8_t>(out, 0);
    Put<int64_t>(out, value);
  };
  auto text = [&](uint8_t key, const std::string& value) {
    Put<uint8_t>(out, key);
    Put<uint8_t>(out, 4);
    Put<uint8_t>(out, static_cast<uint8_t>(value.size()));
    out.insert(out.end(), value.begin(), value.end());
  };
  text(0, "gpu-1");       // name
  text(2, "memq://");     // lcm_url
  integer(5, 3);          // max_sessions
  integer(9, 2000000);    // max_triangles_per_session
  integer(13, 1 << 20);   // ring_bytes
  integer(15, 512);       // max_resolution
  Put<uint8_t>(out, 16);  // max_requests_per_second, a double
  Put<uint8_t>(out, 2);
  Put<double>(out, 100.5);
  text(22, "debug");  // log_level
  Write("daemon_config", "typed_members", out);
}

}  // namespace
}  // namespace far::fuzz

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <output folder>\n", argv[0]);
    return 2;
  }
  far::fuzz::g_out = argv[1];
  far::fuzz::LcmMessageSeeds();
  far::fuzz::SealedMessageSeeds();
  far::fuzz::DaemonDatagramSeeds();
  far::fuzz::SocketHandshakeSeeds();
  far::fuzz::OpenReplySeeds();
  far::fuzz::RingReaderSeeds();
  far::fuzz::RingRecordSeeds();
  far::fuzz::MeshSeeds();
  far::fuzz::DaemonConfigSeeds();
  return 0;
}
