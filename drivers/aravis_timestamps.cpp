#include "drivers/aravis_timestamps.hpp"
#include "drivers/monotonic_clock.hpp"
#include "dsp/core/stamp.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <stdexcept>

namespace rsd::drivers {

namespace {

int64_t read_clock(clockid_t id) {
  timespec ts;
  clock_gettime(id, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

int64_t seconds_to_ns(double s) { return std::llround(s * 1e9); }

}  // namespace

HostClocks from_narrowest(const ClockBracket* brackets, size_t n) {
  const ClockBracket* best = std::min_element(brackets, brackets + n, [](const ClockBracket& a, const ClockBracket& b) {
    return a.monotonic_after_ns - a.monotonic_before_ns < b.monotonic_after_ns - b.monotonic_before_ns;
  });
  return {best->realtime_ns, best->monotonic_before_ns + (best->monotonic_after_ns - best->monotonic_before_ns) / 2};
}

HostClocks read_host_clocks() {
  constexpr size_t kMaxTries = 8;
  constexpr int64_t kNarrowNs = 2000;  // a few clock reads: no preemption inside
  std::array<ClockBracket, kMaxTries> b;
  size_t n = 0;
  while (n < kMaxTries) {
    ClockBracket& r = b[n++];
    r.monotonic_before_ns = read_clock(CLOCK_MONOTONIC);
    r.realtime_ns = read_clock(CLOCK_REALTIME);
    r.monotonic_after_ns = read_clock(CLOCK_MONOTONIC);
    if (r.monotonic_after_ns - r.monotonic_before_ns <= kNarrowNs) break;
  }
  return from_narrowest(b.data(), n);
}

int64_t checked_stamp(uint64_t raw) {
  if (raw > static_cast<uint64_t>(dsp::Stamp::kLimitNs)) return 0;
  return dsp::Stamp::from_ns(static_cast<int64_t>(raw))->ns();
}

int64_t host_stamp_to_monotonic(int64_t host_stamp_ns, const HostClocks& now) {
  if (host_stamp_ns <= 0) return now.monotonic_ns;
  // The stamp is from the recent past, so its own clock reads nearest to it now.
  const int64_t from_realtime = std::llabs(now.realtime_ns - host_stamp_ns);
  const int64_t from_monotonic = std::llabs(now.monotonic_ns - host_stamp_ns);
  if (from_realtime <= from_monotonic) return host_stamp_ns - (now.realtime_ns - now.monotonic_ns);
  return host_stamp_ns;
}

int64_t ReceiptModel::receipt_delay_ns() const {
  const double before_readout = stamp == CameraStamp::ExposureStart ? exposure_s : 0.0;
  return seconds_to_ns(before_readout + leader_delay_s);
}

int64_t ReceiptModel::first_row_ns(int64_t stamp_on_host_ns) const {
  return stamp == CameraStamp::ExposureEnd ? stamp_on_host_ns - seconds_to_ns(exposure_s) : stamp_on_host_ns;
}

CameraClockMapper::CameraClockMapper(ClockMapperOptions opt) : opt_(opt) {
  if (opt_.window < 2) throw std::invalid_argument("CameraClockMapper: window must be at least 2 frames");
  x_.resize(opt_.window);
  y_.resize(opt_.window);
  hull_.reserve(opt_.window);
}

void CameraClockMapper::clear() {
  head_ = count_ = 0;
  slope_ = x_mean_ = y_at_mean_ = 0;
}

int64_t CameraClockMapper::to_host(int64_t camera_ns) const {
  const double dx = static_cast<double>(camera_ns - x_ref_);
  const int64_t y = y_ref_ + std::llround(y_at_mean_ + slope_ * (dx - x_mean_));
  return camera_ns + y;
}

bool CameraClockMapper::off_the_line(int64_t camera_ns, int64_t host_bound_ns) const {
  if (camera_ns <= x_[index(count_ - 1)]) return true;  // the camera clock went back
  const int64_t residual = host_bound_ns - to_host(camera_ns);
  return residual < -seconds_to_ns(opt_.reset_below_s) || residual > seconds_to_ns(opt_.reset_above_s);
}

int64_t CameraClockMapper::add(int64_t camera_ns, int64_t host_bound_ns) {
  if (count_ > 0 && off_the_line(camera_ns, host_bound_ns)) {
    clear();
    ++resets_;
  }
  const size_t slot = index(count_ < x_.size() ? count_ : 0);
  x_[slot] = camera_ns;
  y_[slot] = host_bound_ns - camera_ns;
  if (count_ < x_.size())
    ++count_;
  else
    head_ = (head_ + 1) % x_.size();  // the oldest frame made room
  refit();
  return to_host(camera_ns);
}

// Slope of the lower convex hull's edge above x (window coordinates relative to the refs).
double CameraClockMapper::hull_slope_at(double x) {
  auto px = [&](size_t i) { return static_cast<double>(x_[index(i)] - x_ref_); };
  auto py = [&](size_t i) { return static_cast<double>(y_[index(i)] - y_ref_); };
  auto& hull = hull_;  // scratch, allocated once
  hull.clear();
  for (size_t i = 0; i < count_; ++i) {  // monotone chain; camera stamps only increase
    while (hull.size() >= 2) {
      const size_t a = hull[hull.size() - 2], b = hull.back();
      const double cross = (px(b) - px(a)) * (py(i) - py(a)) - (py(b) - py(a)) * (px(i) - px(a));
      if (cross > 0) break;  // a left turn keeps b on the lower hull
      hull.pop_back();
    }
    hull.push_back(i);
  }
  for (size_t k = 0; k + 1 < hull.size(); ++k)
    if (px(hull[k + 1]) >= x) return (py(hull[k + 1]) - py(hull[k])) / (px(hull[k + 1]) - px(hull[k]));
  return 0;
}

void CameraClockMapper::refit() {
  x_ref_ = x_[index(0)];
  y_ref_ = y_[index(0)];
  double sum = 0;
  for (size_t i = 0; i < count_; ++i) sum += static_cast<double>(x_[index(i)] - x_ref_);
  x_mean_ = sum / static_cast<double>(count_);
  const double span_s = static_cast<double>(x_[index(count_ - 1)] - x_ref_) * 1e-9;
  slope_ = 0;
  if (span_s >= opt_.min_drift_span_s)
    slope_ = std::clamp(hull_slope_at(x_mean_), -opt_.max_drift, opt_.max_drift);
  // The highest line of that slope under every frame, read at the mean.
  double lowest = 0;
  for (size_t i = 0; i < count_; ++i) {
    const double dx = static_cast<double>(x_[index(i)] - x_ref_) - x_mean_;
    const double v = static_cast<double>(y_[index(i)] - y_ref_) - slope_ * dx;
    if (i == 0 || v < lowest) lowest = v;
  }
  y_at_mean_ = lowest;
}

uint64_t FrameCounter::next(uint64_t frame_id) {
  constexpr uint64_t kMax16 = 0xFFFF, kWrapSlack = 4096;
  if (!started_) {
    started_ = true;
    count_ = frame_id;
  } else if (frame_id > last_id_) {
    count_ += frame_id - last_id_;
  } else if (last_id_ <= kMax16 && last_id_ > kMax16 - kWrapSlack && frame_id >= 1 && frame_id < kWrapSlack) {
    count_ += (kMax16 - last_id_) + frame_id;  // 65535 -> 1 is one frame on
  } else {
    count_ += 1;
    ++restarts_;
  }
  last_id_ = frame_id;
  return count_;
}

}  // namespace rsd::drivers
