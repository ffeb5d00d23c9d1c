// Fuzz target gpu_cost_cache: far-daemon's GPU cost cache file (server/src/gpu_cost_cache.h),
// which a start reads before it serves. The file is the daemon's own, but a disk, a crash mid-
// copy or another program can leave anything there, and a start must never fail on it.
//
// Input: the file's bytes. Each is written to a file and read for the key "k".
//
// Oracles besides the sanitizers: a cost read back has every part finite and in [0, 10^6] ms,
// and the gpu pair whole or absent; writing a cost over whatever the file holds succeeds and
// reads back exactly.

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "fuzz_input.h"
#include "gpu_cost_cache.h"

namespace far::fuzz {
namespace {

constexpr int64_t kNow = 1'800'000'000;

bool InRange(double ms) { return std::isfinite(ms) && ms >= 0 && ms <= 1e6; }

// A folder of this process's, removed at exit.
const std::string& CachePath() {
  static const std::string directory = "/tmp/far-fuzz-gpu-cost-" + std::to_string(getpid());
  static const std::string path = [] {
    std::atexit([] { std::filesystem::remove_all(directory); });
    return directory + "/gpu-costs.json";
  }();
  return path;
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far::server;
  const std::string& path = far::fuzz::CachePath();
  far::GpuCost kept{1.5, 2e-5};
  // The directory first (made by the first write), then the input over the file.
  if (!WriteCachedGpuCost(path, "seed", kept, far::fuzz::kNow).ok()) std::abort();
  if (std::FILE* file = std::fopen(path.c_str(), "wb")) {
    if (size > 0) std::fwrite(data, 1, size, file);
    std::fclose(file);
  }
  auto read = ReadCachedGpuCost(path, "k", far::fuzz::kNow);
  if (read.ok() && *read) {
    const far::GpuCost& cost = **read;
    FAR_FUZZ_CHECK(far::fuzz::InRange(cost.fixed_ms) && far::fuzz::InRange(cost.ms_per_triangle));
    FAR_FUZZ_CHECK(cost.compute_fixed_ms.has_value() == cost.compute_ms_per_triangle.has_value());
    if (cost.compute_fixed_ms) {
      FAR_FUZZ_CHECK(far::fuzz::InRange(*cost.compute_fixed_ms) &&
                     far::fuzz::InRange(*cost.compute_ms_per_triangle));
    }
  }
  kept.compute_fixed_ms = 0.25;
  kept.compute_ms_per_triangle = 1e-6;
  FAR_FUZZ_CHECK(WriteCachedGpuCost(path, "k", kept, far::fuzz::kNow).ok());
  auto again = ReadCachedGpuCost(path, "k", far::fuzz::kNow);
  FAR_FUZZ_CHECK(again.ok() && *again && **again == kept);
  return 0;
}
