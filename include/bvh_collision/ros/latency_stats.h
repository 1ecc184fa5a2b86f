// Per-service request counts and latency percentiles for /diagnostics: the last kWindow
// durations in a ring, so percentiles describe recent behaviour and memory stays fixed.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <vector>

namespace bvh_collision {

class LatencyStats {
 public:
  static constexpr std::size_t kWindow = 4096;

  struct Summary {
    std::uint64_t requests = 0, errors = 0;
    std::uint64_t in_progress = 0;  // begun, not yet recorded
    double p50 = 0.0, p90 = 0.0, p99 = 0.0, max = 0.0;  // seconds, over the window
  };

  // A request has begun; record() ends it.
  void begin() {
    std::lock_guard<std::mutex> lock(mutex_);
    ++in_progress_;
  }

  void record(double seconds, bool error) {
    std::lock_guard<std::mutex> lock(mutex_);
    --in_progress_;  // after its begin()
    ring_[requests_ % kWindow] = seconds;
    ++requests_;
    if (error) ++errors_;
  }

  Summary summary() const {
    std::vector<double> window;
    Summary s;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      s.requests = requests_;
      s.errors = errors_;
      s.in_progress = in_progress_;
      window.assign(ring_.begin(), ring_.begin() + std::min<std::uint64_t>(requests_, kWindow));
    }
    if (window.empty()) return s;
    std::sort(window.begin(), window.end());
    const auto at = [&](double q) { return window[std::min(window.size() - 1, std::size_t(q * window.size()))]; };
    s.p50 = at(0.50);
    s.p90 = at(0.90);
    s.p99 = at(0.99);
    s.max = window.back();
    return s;
  }

 private:
  mutable std::mutex mutex_;
  std::array<double, kWindow> ring_{};
  std::uint64_t requests_ = 0, errors_ = 0, in_progress_ = 0;
};

}  // namespace bvh_collision
