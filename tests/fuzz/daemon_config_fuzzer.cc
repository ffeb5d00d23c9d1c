// Fuzz target daemon_config: far-daemon's JSON configuration parser (ParseDaemonConfig, what
// LoadDaemonConfig runs on the file given with --config).
//
// Input: JSON text, as an operator writes it; or, when the first byte is 0xff, a configuration
// built from typed members, so that every key meets every JSON type and the edges of every
// integer range (text mutations rarely turn a whole valid file into one with an extreme value):
// members until the bytes run out, each
//   uint8 key     index into kKeys (the known keys, then one unknown)
//   uint8 kind    % 6: 0 int64, 1 uint64, 2 double (8 bytes each, host order), 3 bool (1 byte),
//                 4 string (uint8 length, then bytes), 5 null
// The object is written as JSON text (nlohmann) and parsed like a file.
//
// Oracles besides the sanitizers: an accepted configuration passes ValidateDaemonConfig, the
// budgets derived from it (SceneLimitsOf, RingLimitsOf) are positive, and its socket path and
// channel prefix can be made (SocketPathOf, ChannelPrefix).

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "daemon_config.h"
#include "fuzz_input.h"
#include <nlohmann/json.hpp>

namespace far::fuzz {
namespace {

constexpr const char* kKeys[] = {
    "name",
    "socket_path",
    "lcm_url",
    "gl_platform",
    "gpu",
    "max_sessions",
    "max_sessions_per_user",
    "max_opens_per_second_per_user",
    "max_objects_per_session",
    "max_triangles_per_session",
    "max_vertices_per_session",
    "max_triangles_total",
    "max_vertices_total",
    "ring_bytes",
    "reply_bytes",
    "max_resolution",
    "max_requests_per_second",
    "max_queued_per_session",
    "max_reply_pairs",
    "step_deadline_ms",
    "heavy_step_ms",
    "status_after_ms",
    "setup_allowance_ms",
    "exact_threads",
    "cpu_cores",
    "log_level",
    "no_such_key",
};

nlohmann::json ValueOf(uint8_t kind, FuzzInput& in) {
  switch (kind % 6) {
    case 0:
      return in.Take<int64_t>();
    case 1:
      return in.Take<uint64_t>();
    case 2:
      return in.Take<double>();
    case 3:
      return (in.Take<uint8_t>() & 1) != 0;
    case 4: {
      const auto bytes = in.TakeBytes(in.Take<uint8_t>());
      return std::string(bytes.begin(), bytes.end());
    }
    default:
      return nullptr;
  }
}

// The typed-members form of the input, as JSON text.
std::string StructuredConfig(FuzzInput& in) {
  nlohmann::json object = nlohmann::json::object();
  while (!in.empty()) {
    const char* key = kKeys[in.Take<uint8_t>() % std::size(kKeys)];
    object[key] = ValueOf(in.Take<uint8_t>(), in);
  }
  // Strings may hold any bytes: replace invalid UTF-8 instead of throwing.
  return object.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far::server;
  std::string structured;
  std::string_view text(reinterpret_cast<const char*>(data), size);
  if (size > 0 && data[0] == 0xff) {
    far::fuzz::FuzzInput in(data + 1, size - 1);
    structured = far::fuzz::StructuredConfig(in);
    text = structured;
  }
  auto config = ParseDaemonConfig(text, "fuzz.json");
  if (!config) return 0;
  FAR_FUZZ_CHECK(ValidateDaemonConfig(*config).ok());
  const far::SceneLimits scene = SceneLimitsOf(*config);
  FAR_FUZZ_CHECK(scene.max_objects > 0 && scene.max_triangles > 0 && scene.max_vertices > 0);
  const far::protocol::RingLimits ring = RingLimitsOf(*config);
  FAR_FUZZ_CHECK(ring.max_vertices > 0 && ring.max_triangles > 0);
  FAR_FUZZ_CHECK(!SocketPathOf(*config).empty());
  FAR_FUZZ_CHECK(far::protocol::ChannelPrefix(config->name).starts_with("FAR_"));
  return 0;
}
