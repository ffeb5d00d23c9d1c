#pragma once

#include <cstddef>
#include <vector>

#include "far/base/quantile.h"

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

  /// Returns the q-quantile (0..1) of the window (far::Quantile), 0 when empty.
  double Quantile(double q) const { return far::Quantile(samples_, q); }

  size_t count() const { return count_; }

 private:
  size_t window_;
  std::vector<double> samples_;
  size_t next_ = 0;
  size_t count_ = 0;
};

}  // namespace far::server
