// Latency from last row read to publish: a fixed histogram (0.01 ms bins up to 100 ms) that
// the publisher thread fills and the health reporter reads and resets once a second. A latency
// beyond the histogram's range is counted apart (over_range), never clipped into its last bin:
// a quantile that falls there is reported as the largest latency seen, an upper bound.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>

namespace rsd::daemon {

class LatencyStats {
 public:
  static constexpr int kBins = 10000;
  static constexpr double kBinMs = 0.01;
  static constexpr double kRangeMs = kBins * kBinMs;
  void add(double ms) {
    if (ms >= kRangeMs) over_.fetch_add(1, std::memory_order_relaxed);
    else bins_[ms < 0 ? 0 : std::min(kBins - 1, static_cast<int>(ms / kBinMs))].fetch_add(1, std::memory_order_relaxed);
    if (ms > max_ms_.load(std::memory_order_relaxed)) max_ms_.store(ms, std::memory_order_relaxed);  // one writer
  }
  // The q-quantile (0..1) in ms of what was added since the last reset; 0 if nothing.
  double quantile(double q) const {
    uint64_t total = over_range();
    for (const auto& b : bins_) total += b.load(std::memory_order_relaxed);
    if (total == 0) return 0;
    const uint64_t want = static_cast<uint64_t>(q * static_cast<double>(total - 1)) + 1;
    uint64_t acc = 0;
    for (int i = 0; i < kBins; ++i)
      if ((acc += bins_[i].load(std::memory_order_relaxed)) >= want) return (i + 0.5) * kBinMs;
    return max_ms();  // beyond the range: the largest seen bounds it
  }
  // Latencies at or beyond kRangeMs since the last reset.
  uint64_t over_range() const { return over_.load(std::memory_order_relaxed); }
  double max_ms() const { return max_ms_.load(std::memory_order_relaxed); }
  void reset() {
    for (auto& b : bins_) b.store(0, std::memory_order_relaxed);
    over_.store(0, std::memory_order_relaxed);
    max_ms_.store(0, std::memory_order_relaxed);
  }

 private:
  std::array<std::atomic<uint64_t>, kBins> bins_{};
  std::atomic<uint64_t> over_{0};
  std::atomic<double> max_ms_{0};
};

}  // namespace rsd::daemon
