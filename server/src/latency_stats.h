#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace far::server {

/// Percentiles of the most recent `window` samples (milliseconds). Not thread-safe.
class LatencyWindow {
 public:
  explicit LatencyWindow(size_t window = 4096) : window_(window) { samples_.reserve(window); }

  void Add(double ms) {
    if (samples_.size() < window_) {
      samples_.push_back(ms);
    } else {
      samples_[next_] = ms;
    }
    next_ = (next_ + 1) % window_;
    ++count_;
  }

  /// Returns the q-quantile (0..1) of the window by nearest rank, 0 when empty.
  double Quantile(double q) const {
    if (samples_.empty()) return 0;
    std::vector<double> sorted = samples_;
    const size_t rank =
        std::min(sorted.size() - 1, static_cast<size_t>(q * static_cast<double>(sorted.size())));
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(rank),
                     sorted.end());
    return sorted[rank];
  }

  size_t count() const { return count_; }

 private:
  size_t window_;
  std::vector<double> samples_;
  size_t next_ = 0;
  size_t count_ = 0;
};

}  // namespace far::server
