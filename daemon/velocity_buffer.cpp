#include "daemon/velocity_buffer.hpp"

#include <algorithm>
#include <cmath>

namespace rsd::daemon {

namespace {

double norm3(const double* a) { return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]); }

drivers::VelocitySample lerp(const drivers::VelocitySample& a, const drivers::VelocitySample& b, int64_t t) {
  const double f = b.t_ns > a.t_ns ? static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns) : 0.0;
  drivers::VelocitySample s = a;
  s.t_ns = t;
  for (int i = 0; i < 3; ++i) {
    s.w[i] = a.w[i] + f * (b.w[i] - a.w[i]);
    s.v[i] = a.v[i] + f * (b.v[i] - a.v[i]);
  }
  s.has_linear = a.has_linear && b.has_linear;
  return s;
}

}  // namespace

bool VelocityBuffer::sane(const drivers::VelocitySample& s) const {
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(s.w[i]) || (s.has_linear && !std::isfinite(s.v[i]))) return false;
  return norm3(s.w) <= limits_.max_angular_rad_s && (!s.has_linear || norm3(s.v) <= limits_.max_linear_m_s);
}

void VelocityBuffer::append(const drivers::VelocitySample& s) {
  const uint64_t n = count_.load(std::memory_order_relaxed);
  ring_[n % kCapacity] = s;
  count_.store(n + 1, std::memory_order_release);
  newest_ns_.store(s.t_ns, std::memory_order_release);
}

// The held samples and `s` are a new time line (dsp::TimeLine): readers see only its samples.
bool VelocityBuffer::take_new_line(const drivers::VelocitySample& s) {
  const int held = kNewTimeLine - 1;  // counted as rejected while held (what a reader cannot see)
  rejected_.fetch_sub(static_cast<uint64_t>(held), std::memory_order_relaxed);
  // Published before the samples' count, so a reader that sees them sees the new epoch.
  epoch_.store(count_.load(std::memory_order_relaxed), std::memory_order_release);
  time_lines_.fetch_add(1, std::memory_order_relaxed);
  for (int i = 0; i < held; ++i) append(candidates_[static_cast<size_t>(i)]);
  append(s);
  return true;
}

bool VelocityBuffer::push(const drivers::VelocitySample& s) {
  if (!sane(s)) {
    rejected_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  switch (line_.offer(s.t_ns)) {
    case dsp::TimeLine::Verdict::Continues:
      append(s);
      return true;
    case dsp::TimeLine::Verdict::Held:
      rejected_.fetch_add(1, std::memory_order_relaxed);  // uncounted if a new line confirms it
      candidates_[static_cast<size_t>(line_.held() - 1)] = s;
      return false;
    case dsp::TimeLine::Verdict::Replaces:
      return take_new_line(s);
  }
  return false;
}

int64_t VelocityBuffer::newest_ns(uint64_t horizon) const {
  for (int attempt = 0; attempt < 4; ++attempt) {
    const uint64_t count = count_.load(std::memory_order_acquire);
    const uint64_t n = std::min(count, horizon);
    if (n == 0 || count - n >= kCapacity / 2) return INT64_MIN;  // none, or overwritten soon
    const int64_t t = ring_[(n - 1) % kCapacity].t_ns;
    if (count_.load(std::memory_order_acquire) - n < kCapacity / 2) return t;  // not lapped meanwhile
  }
  return INT64_MIN;
}

VelocityStatus VelocityBuffer::at(int64_t t_ns, VelocityEstimate& out, uint64_t horizon) const {
  const int64_t max_age_ns = static_cast<int64_t>(limits_.max_age_s * 1e9);
  for (int attempt = 0; attempt < 4; ++attempt) {
    const uint64_t count = count_.load(std::memory_order_acquire);
    const uint64_t n = std::min(count, horizon);
    if (n == 0) return VelocityStatus::NoData;
    // Read only the newer half of the ring, so a writer running ahead cannot lap the reader
    // unless it writes half a ring of samples meanwhile (checked below), and only the current
    // time line.
    const uint64_t epoch = epoch_.load(std::memory_order_acquire);
    if (epoch >= n && n < count) return VelocityStatus::NoData;  // the horizon's line was replaced
    if (epoch >= n) continue;  // a new time line is being written: read again
    if (count - n >= kCapacity / 2) return VelocityStatus::Stale;  // the horizon's samples are being overwritten
    const uint64_t lo = std::max(n > kCapacity / 2 ? n - kCapacity / 2 : 0, epoch);
    uint64_t i = n - 1;
    while (i > lo && ring_[i % kCapacity].t_ns > t_ns) --i;
    const drivers::VelocitySample a = ring_[i % kCapacity];
    const drivers::VelocitySample b = i + 1 < n ? ring_[(i + 1) % kCapacity] : a;
    if (count_.load(std::memory_order_acquire) - lo > kCapacity) continue;  // lapped: read again
    if (epoch_.load(std::memory_order_acquire) != epoch) continue;        // a new time line meanwhile
    if (a.t_ns > t_ns) return VelocityStatus::Stale;  // older than anything we hold
    if (b.t_ns > t_ns) {  // bracketed: interpolate, unless the samples are too far apart
      if (b.t_ns - a.t_ns > 2 * max_age_ns) return VelocityStatus::Stale;
      out.sample = lerp(a, b, t_ns);
      out.age_s = 0;
      return VelocityStatus::Ok;
    }
    out.age_s = static_cast<double>(t_ns - a.t_ns) * 1e-9;  // after the newest: hold it
    if (t_ns - a.t_ns > max_age_ns) return VelocityStatus::Stale;
    out.sample = a;
    out.sample.t_ns = t_ns;
    return VelocityStatus::Ok;
  }
  return VelocityStatus::Stale;
}

}  // namespace rsd::daemon
