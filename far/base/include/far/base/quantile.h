#pragma once

// One quantile for every latency and timing table: the daemon's status, far-client load and
// the studies.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace far {

/// Returns the q-quantile (q in [0, 1]) of `samples`, interpolated linearly between the two
/// nearest ranks of the sorted samples (numpy's default): q = 0 is the minimum, q = 1 the
/// maximum, q = 0.5 of {1, 2, 3, 4} is 2.5. 0 when `samples` is empty. Takes a copy.
inline double Quantile(std::vector<double> samples, double q) {
  if (samples.empty()) return 0;
  std::sort(samples.begin(), samples.end());
  const double position = std::clamp(q, 0.0, 1.0) * static_cast<double>(samples.size() - 1);
  const auto low = static_cast<size_t>(std::floor(position));
  const size_t high = std::min(low + 1, samples.size() - 1);
  return samples[low] + (position - static_cast<double>(low)) * (samples[high] - samples[low]);
}

}  // namespace far
