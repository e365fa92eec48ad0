// Latency from last row read to publish: a fixed histogram (0.01 ms bins up to 100 ms) that
// the publisher thread fills and the health reporter reads and resets once a second.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>

namespace rsd::daemon {

class LatencyStats {
 public:
  static constexpr int kBins = 10000;
  static constexpr double kBinMs = 0.01;
  void add(double ms) {
    const int b = ms < 0 ? 0 : (ms >= kBins * kBinMs ? kBins - 1 : static_cast<int>(ms / kBinMs));
    bins_[b].fetch_add(1, std::memory_order_relaxed);
    if (ms > max_ms_.load(std::memory_order_relaxed)) max_ms_.store(ms, std::memory_order_relaxed);  // one writer
  }
  // The q-quantile (0..1) in ms of what was added since the last reset; 0 if nothing.
  double quantile(double q) const {
    uint64_t total = 0;
    for (const auto& b : bins_) total += b.load(std::memory_order_relaxed);
    if (total == 0) return 0;
    const uint64_t want = static_cast<uint64_t>(q * static_cast<double>(total - 1)) + 1;
    uint64_t acc = 0;
    for (int i = 0; i < kBins; ++i)
      if ((acc += bins_[i].load(std::memory_order_relaxed)) >= want) return (i + 0.5) * kBinMs;
    return kBins * kBinMs;
  }
  double max_ms() const { return max_ms_.load(std::memory_order_relaxed); }
  void reset() {
    for (auto& b : bins_) b.store(0, std::memory_order_relaxed);
    max_ms_.store(0, std::memory_order_relaxed);
  }

 private:
  std::array<std::atomic<uint64_t>, kBins> bins_{};
  std::atomic<double> max_ms_{0};
};

}  // namespace rsd::daemon
