// The recent velocity samples (camera axes), written by one thread (the velocity input:
// LCM receiver or the simulated camera) and read by the rectifier without locks: a ring of
// plain samples with a published write count; a reader copies what it needs and checks that
// the writer did not lap it meanwhile (a seqlock on the whole window).
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <optional>

#include "drivers/camera_source.hpp"
#include "dsp/core/time_line.hpp"

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
  explicit VelocityBuffer(VelocityLimits limits = {})
      : limits_(limits),
        max_jump_ns_(std::max<int64_t>(1'000'000'000, static_cast<int64_t>(2e9 * limits.max_age_s))),
        line_(max_jump_ns_, kNewTimeLine) {}

  // A sample more than max_jump_ns() after the newest (1 s, or twice max_age_s if longer: the
  // widest gap the buffer interpolates across), or not after it, is off the current time line.
  int64_t max_jump_ns() const { return max_jump_ns_; }
  // This many consecutive off-line samples that form a time line of their own replace the
  // current one: the clock jumped or restarted, or the current line began with a wild stamp
  // (one far-future sample must not make every later one "late" until a restart).
  static constexpr int kNewTimeLine = 8;

  // Writer: rejects (and counts) samples that break the sanity limits; holds samples off the
  // current time line until they confirm a new one (see kNewTimeLine), then takes them all.
  bool push(const drivers::VelocitySample& s);
  // Writer: counts a sample refused before it could be pushed (a stamp out of range, far from
  // the clock).
  void reject() { rejected_.fetch_add(1, std::memory_order_relaxed); }

  // Every sample pushed so far: a reader's default horizon.
  static constexpr uint64_t kAll = UINT64_MAX;

  // Reader: the velocity at t_ns, linearly interpolated between the samples around it (or
  // the newest one, if t is after it but within max_age). Only the first `horizon` samples
  // ever pushed count (a count() taken earlier): a replayed frame sees the samples that came
  // before it in the log, however far the reader has gone on meanwhile.
  VelocityStatus at(int64_t t_ns, VelocityEstimate& out, uint64_t horizon = kAll) const;

  // Reader: the newest accepted sample's time (INT64_MIN before the first); any thread.
  int64_t newest_ns() const { return newest_ns_.load(std::memory_order_acquire); }
  // Reader: the newest time among the first `horizon` samples (INT64_MIN: none readable).
  int64_t newest_ns(uint64_t horizon) const;

  uint64_t rejected() const { return rejected_.load(std::memory_order_relaxed); }
  // How often a new time line replaced the current one.
  uint64_t time_line_changes() const { return time_lines_.load(std::memory_order_relaxed); }
  uint64_t count() const { return count_.load(std::memory_order_acquire); }

 private:
  bool sane(const drivers::VelocitySample& s) const;
  bool take_new_line(const drivers::VelocitySample& s);
  void append(const drivers::VelocitySample& s);
  VelocityLimits limits_;
  int64_t max_jump_ns_;
  dsp::TimeLine line_;                                                // writer only
  std::array<drivers::VelocitySample, kNewTimeLine> candidates_{};  // writer only: the held samples
  std::atomic<uint64_t> epoch_{0};  // index of the current time line's first sample
  std::atomic<uint64_t> time_lines_{0};
  std::array<drivers::VelocitySample, kCapacity> ring_{};
  std::atomic<uint64_t> count_{0};
  std::atomic<uint64_t> rejected_{0};
  std::atomic<int64_t> newest_ns_{INT64_MIN};  // line_.newest(), published for readers
};

}  // namespace rsd::daemon
