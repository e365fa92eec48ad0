#include "drivers/libcamera_logic.hpp"

#include <libcamera/formats.h>

#include "dsp/core/stamp.hpp"

#include <algorithm>
#include <vector>

namespace rsd::drivers::lc {

// ---- Pixel formats -------------------------------------------------------------------------

namespace {

using PF = dsp::PixelFormat;

// libcamera names formats by their packed words, little-endian: BGR888 is R, G, B in memory.
const std::vector<FormatInfo>& formats() {
  namespace f = libcamera::formats;
  static const std::vector<FormatInfo> table{
      {f::R8, "R8", v4l2::Layout::Grey8},
      {f::BGR888, "BGR888", v4l2::Layout::Rgb24},  // memory R, G, B
      {f::RGB888, "RGB888", v4l2::Layout::Bgr24},  // memory B, G, R
      {f::YUYV, "YUYV", v4l2::native(PF::Yuyv)},
      {f::NV12, "NV12", v4l2::native(PF::Nv12)},
      {f::YUV420, "YUV420", v4l2::native(PF::I420)},
      {f::SRGGB8, "SRGGB8", v4l2::native(PF::BayerRggb8)},
      {f::SBGGR8, "SBGGR8", v4l2::native(PF::BayerBggr8)},
      {f::SGRBG8, "SGRBG8", v4l2::native(PF::BayerGrbg8)},
      {f::SGBRG8, "SGBRG8", v4l2::native(PF::BayerGbrg8)},
      {f::SRGGB16, "SRGGB16", v4l2::native(PF::BayerRggb16)},
      {f::SBGGR16, "SBGGR16", v4l2::native(PF::BayerBggr16)},
      {f::SGRBG16, "SGRBG16", v4l2::native(PF::BayerGrbg16)},
      {f::SGBRG16, "SGBRG16", v4l2::native(PF::BayerGbrg16)},
  };
  return table;
}

}  // namespace

const FormatInfo* format_info(const libcamera::PixelFormat& f) {
  for (const auto& i : formats())
    if (i.format == f) return &i;
  return nullptr;
}

// The formats that deliver `want` itself first (RGB: BGR888 copies straight into R, G, B slots,
// RGB888 needs a swap; grey: R8; 16-bit grey: R8 too, libcamera 0.0.3 has no 16-bit grey an
// ISP would deliver), then YUYV, NV12, I420 (a colour camera's usual output, rectified
// natively), then the raw mosaics.
std::vector<FormatInfo> candidates(dsp::PixelFormat want) {
  if (want == PF::Mono16) want = PF::Mono8;
  std::vector<FormatInfo> out;
  for (const auto& i : formats())
    if (i.layout.format == want) out.push_back(i);
  for (const auto& i : formats())
    if (i.layout.format != want) out.push_back(i);
  return out;
}

std::optional<FormatInfo> choose_format(dsp::PixelFormat want, const std::vector<libcamera::PixelFormat>& offered) {
  for (const auto& c : candidates(want))
    if (std::find(offered.begin(), offered.end(), c.format) != offered.end()) return c;
  return std::nullopt;
}

// ---- Stream role ---------------------------------------------------------------------------

bool parse_role(std::string_view s, Role& out) {
  if (s == "auto") out = Role::Auto;
  else if (s == "viewfinder") out = Role::Viewfinder;
  else if (s == "raw") out = Role::Raw;
  else return false;
  return true;
}

libcamera::StreamRole stream_role(Role r) {
  return r == Role::Raw ? libcamera::StreamRole::Raw : libcamera::StreamRole::Viewfinder;
}

const char* role_name(Role r) { return r == Role::Raw ? "raw" : "viewfinder"; }

// ---- Errors --------------------------------------------------------------------------------

std::string no_camera_message(const std::string& wanted_id, const std::vector<std::string>& listed) {
  std::string s = "no libcamera camera found";
  if (!wanted_id.empty()) s += " with id '" + wanted_id + "'";
  s += " (" + std::to_string(listed.size()) + (listed.size() == 1 ? " camera" : " cameras") + " listed";
  for (std::size_t i = 0; i < listed.size(); ++i) s += (i ? ", " : ": ") + listed[i];
  return s + ")";
}

// ---- Timestamps ----------------------------------------------------------------------------

std::int64_t ClockResolver::to_monotonic(std::int64_t ts, std::int64_t mono_now_ns, std::int64_t boot_now_ns) {
  const std::int64_t suspended = boot_now_ns - mono_now_ns;
  if (!settled_) {
    const auto fits = [&](std::int64_t now) { return now - ts >= 0 && now - ts <= max_latency_ns_; };
    const bool mono = fits(mono_now_ns), boot = fits(boot_now_ns);
    if (mono != boot) settled_ = mono ? Clock::Monotonic : Clock::Boottime;
  }
  return settled_.value_or(Clock::Boottime) == Clock::Monotonic ? ts : ts - suspended;
}

namespace {

// A stamp the sensor or buffer gives, through rsd's one check for times from outside
// (dsp::Stamp): positive and within the window, else not used.
bool usable(std::int64_t ns) { return ns > 0 && dsp::Stamp::from_ns(ns).has_value(); }

}  // namespace

FirstRowStamp first_row_stamp(const Completion& c, ClockResolver& clocks, int rows, double line_delay_s,
                              double exposure_s) {
  if (c.sensor_timestamp_ns && usable(*c.sensor_timestamp_ns))
    return {clocks.to_monotonic(*c.sensor_timestamp_ns, c.mono_now_ns, c.boot_now_ns), StampOrigin::SensorTimestamp};
  if (c.buffer_timestamp_ns <= static_cast<std::uint64_t>(dsp::Stamp::kLimitNs) &&
      usable(static_cast<std::int64_t>(c.buffer_timestamp_ns)))
    return {clocks.to_monotonic(static_cast<std::int64_t>(c.buffer_timestamp_ns), c.mono_now_ns, c.boot_now_ns),
            StampOrigin::BufferTimestamp};
  return {v4l2::first_row_from_end_of_frame(c.mono_now_ns, rows, line_delay_s, exposure_s),
          StampOrigin::CompletionTime};
}

double exposure_seconds(std::optional<std::int32_t> exposure_us, double fallback_s) {
  return exposure_us && *exposure_us > 0 ? *exposure_us * 1e-6 : fallback_s;
}

// ---- Mapping a dmabuf plane ----------------------------------------------------------------

MapSpan page_span(std::size_t plane_offset, std::size_t plane_length, std::size_t page_size) {
  MapSpan s;
  s.map_offset = page_size ? plane_offset - plane_offset % page_size : plane_offset;
  s.data_offset = plane_offset - s.map_offset;
  s.map_length = s.data_offset + plane_length;
  return s;
}

// ---- Request bookkeeping -------------------------------------------------------------------

Disposition dispose(const Completion& c) {
  if (c.cancelled) return Disposition::Retire;
  return c.frame_ok ? Disposition::Deliver : Disposition::Skip;
}

void CompletionQueue::queued() {
  std::lock_guard lock(m_);
  ++in_flight_;
}

void CompletionQueue::push(Completion c) {
  {
    std::lock_guard lock(m_);
    if (in_flight_ > 0) --in_flight_;
    done_.push_back(std::move(c));
  }
  cv_.notify_one();
}

void CompletionQueue::lose() {
  {
    std::lock_guard lock(m_);
    lost_ = true;
  }
  cv_.notify_all();
}

WaitResult CompletionQueue::pop(std::chrono::milliseconds timeout, Completion& out) {
  std::unique_lock lock(m_);
  // A frame that completed before the camera went away is still delivered.
  if (!cv_.wait_for(lock, timeout, [this] { return !done_.empty() || lost_; })) return WaitResult::Timeout;
  if (done_.empty()) return WaitResult::Lost;
  out = std::move(done_.front());
  done_.pop_front();
  return WaitResult::Ready;
}

std::size_t CompletionQueue::in_flight() const {
  std::lock_guard lock(m_);
  return in_flight_;
}

void CompletionQueue::reset() {
  std::lock_guard lock(m_);
  done_.clear();
  in_flight_ = 0;
  lost_ = false;
}

}  // namespace rsd::drivers::lc
