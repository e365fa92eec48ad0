// The recent velocity samples (camera axes), written by one thread (the velocity input:
// LCM receiver or the simulated camera) and read by the rectifier without locks: a ring of
// plain samples with a published write count; a reader copies what it needs and checks that
// the writer did not lap it meanwhile (a seqlock on the whole window).
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>

#include "drivers/camera_source.hpp"

namespace rsd::daemon {

struct VelocityLimits {
  double max_angular_rad_s = 20.0;  // beyond this a sample is a sensor fault, not motion
  double max_linear_m_s = 100.0;
  double max_age_s = 0.1;           // no sample within this of the frame: velocity invalid
};

struct VelocityEstimate {
  drivers::VelocitySample sample;  // interpolated to the query time
  double age_s = 0;                // query time minus the newest sample used
};

enum class VelocityStatus { Ok, NoData, Stale };

class VelocityBuffer {
 public:
  // Readers look at the newer half: 2048 samples, a second of a 2 kHz IMU. A replay hands
  // samples over ahead of the frames that the pipeline still holds (its slots, plus the clock
  // offset): a few hundred milliseconds of them must stay readable.
  static constexpr size_t kCapacity = 4096;
  explicit VelocityBuffer(VelocityLimits limits = {}) : limits_(limits) {}

  // Writer: rejects (and counts) samples that break the sanity limits or go back in time.
  bool push(const drivers::VelocitySample& s);

  // Reader: the velocity at t_ns, linearly interpolated between the samples around it (or
  // the newest one, if t is after it but within max_age).
  VelocityStatus at(int64_t t_ns, VelocityEstimate& out) const;

  // Reader: the newest accepted sample's time (INT64_MIN before the first); any thread.
  int64_t newest_ns() const { return newest_ns_.load(std::memory_order_acquire); }

  uint64_t rejected() const { return rejected_.load(std::memory_order_relaxed); }
  uint64_t count() const { return count_.load(std::memory_order_acquire); }

 private:
  bool sane(const drivers::VelocitySample& s) const;
  VelocityLimits limits_;
  std::array<drivers::VelocitySample, kCapacity> ring_{};
  std::atomic<uint64_t> count_{0};
  std::atomic<uint64_t> rejected_{0};
  int64_t last_t_ns_ = INT64_MIN;  // writer only
  std::atomic<int64_t> newest_ns_{INT64_MIN};  // last_t_ns_, published for readers
};

}  // namespace rsd::daemon
