// A time from outside (a log's event time, a frame's frame_ns or utime, a velocity or IMU stamp,
// a recording's or camera's time), checked once where it enters: the one way such a time
// becomes a number rsd computes with.
//
// A Stamp lies within +-2^61 ns of its clock's epoch (dsp::limits::kStampLimitNs: 73 years, every
// CLOCK_MONOTONIC and Unix time of a real system). Two stamps subtract exactly, and a stamp moved
// by any offset or duration either stays in the window or is refused: no combination overflows,
// whatever came in. Construction is the check: from_ns, from_us and from_s return nothing for a
// time outside the window (or a NaN), so a caller cannot forget it.
//
// Thread contract: a value type; copies are independent.
#pragma once

#include "dsp/core/input_limits.hpp"

#include <cmath>
#include <compare>
#include <cstdint>
#include <optional>

namespace rsd::dsp {

class Stamp {
 public:
  static constexpr int64_t kLimitNs = limits::kStampLimitNs;
  static constexpr int64_t kLimitUs = kLimitNs / 1000;
  static constexpr double kLimitS = static_cast<double>(kLimitNs) * 1e-9;  // 2.3e9 s

  static constexpr std::optional<Stamp> from_ns(int64_t ns) {
    if (ns < -kLimitNs || ns > kLimitNs) return std::nullopt;
    return Stamp(ns);
  }
  static constexpr std::optional<Stamp> from_us(int64_t us) {
    if (us < -kLimitUs || us > kLimitUs) return std::nullopt;
    return Stamp(us * 1000);
  }
  // Seconds (a recording's times, an images recording's stamps), to the nearest nanosecond.
  static std::optional<Stamp> from_s(double s) {
    if (!(std::abs(s) <= kLimitS)) return std::nullopt;  // NaN too
    return from_ns(std::llround(s * 1e9));
  }

  constexpr int64_t ns() const { return ns_; }
  // Whole microseconds, rounded toward minus infinity (an LCM utime).
  constexpr int64_t us() const { return ns_ >= 0 ? ns_ / 1000 : -((-ns_ + 999) / 1000); }

  // This stamp moved by d_ns (an offset, a duration, another pair's difference): nothing when
  // the result leaves the window. Exact; never overflows, whatever d_ns is.
  constexpr std::optional<Stamp> plus_ns(int64_t d_ns) const {
    int64_t r = 0;
    if (__builtin_add_overflow(ns_, d_ns, &r)) return std::nullopt;
    return from_ns(r);
  }
  // Moved by d_s seconds, rounded to the nanosecond: nothing for a NaN or a result out of window.
  std::optional<Stamp> plus_s(double d_s) const {
    if (!(std::abs(d_s) <= 2 * kLimitS)) return std::nullopt;
    return plus_ns(std::llround(d_s * 1e9));
  }

  // a - b in nanoseconds: exact, as both lie within +-2^61.
  friend constexpr int64_t operator-(Stamp a, Stamp b) { return a.ns_ - b.ns_; }
  friend constexpr auto operator<=>(Stamp, Stamp) = default;

 private:
  explicit constexpr Stamp(int64_t ns) : ns_(ns) {}
  int64_t ns_;
};

}  // namespace rsd::dsp
