#include "formats/image_t_codec.hpp"

#include <charconv>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <utility>

#include "dsp/core/image_planes.hpp"
#include "dsp/core/input_limits.hpp"
#include "dsp/core/stamp.hpp"
#include "formats/number_text.hpp"

namespace rsd::formats {

namespace {

using Img = bot_core::image_t;
using PF = dsp::PixelFormat;

constexpr std::pair<PF, int32_t> kFourcc[] = {
    {PF::Mono8, Img::PIXEL_FORMAT_GRAY},
    {PF::Mono16, Img::PIXEL_FORMAT_LE_GRAY16},
    {PF::Rgb8, Img::PIXEL_FORMAT_RGB},
    {PF::Yuyv, Img::PIXEL_FORMAT_YUYV},
    {PF::Nv12, Img::PIXEL_FORMAT_NV12},
    {PF::I420, Img::PIXEL_FORMAT_I420},
    {PF::BayerRggb8, Img::PIXEL_FORMAT_BAYER_RGGB},
    {PF::BayerBggr8, Img::PIXEL_FORMAT_BAYER_BGGR},
    {PF::BayerGrbg8, Img::PIXEL_FORMAT_BAYER_GRBG},
    {PF::BayerGbrg8, Img::PIXEL_FORMAT_BAYER_GBRG},
    {PF::BayerRggb16, Img::PIXEL_FORMAT_LE_BAYER16_RGGB},
    {PF::BayerBggr16, Img::PIXEL_FORMAT_LE_BAYER16_BGGR},
    {PF::BayerGrbg16, Img::PIXEL_FORMAT_LE_BAYER16_GRBG},
    {PF::BayerGbrg16, Img::PIXEL_FORMAT_LE_BAYER16_GBRG},
};

}  // namespace

int32_t fourcc(dsp::PixelFormat f) {
  for (const auto& [format, code] : kFourcc)
    if (format == f) return code;
  return Img::PIXEL_FORMAT_INVALID;
}

std::optional<dsp::PixelFormat> pixel_format(int32_t fourcc_code) {
  if (fourcc_code == Img::PIXEL_FORMAT_YUV420) return PF::I420;  // the same layout, another name
  for (const auto& [format, code] : kFourcc)
    if (code == fourcc_code) return format;
  return std::nullopt;
}

namespace {

constexpr std::initializer_list<const char*> kKeys = {"frame_utime", "line_delay_ns", "readout", "exposure_ns", "sequence", "rectified",
                             "frame_ns",    "exposure_s",    "timing",  "intrinsics"};
constexpr size_t kValueCapacity = 320;  // the intrinsics: 10 numbers of up to 24 characters and a lens name

std::string value_of(const bot_core::image_t& img, const char* key) {
  for (const auto& m : img.metadata)
    if (m.key == key) return std::string(m.value.begin(), m.value.end());
  return {};
}

template <class T>
bool parse_number(const std::string& s, T& out) {
  if (s.empty()) return false;
  if constexpr (std::is_floating_point_v<T>) {
    char* end = nullptr;
    out = std::strtod(s.c_str(), &end);  // reads "%.17g" back exactly
    return end && *end == '\0';
  } else {
    const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
  }
}

// "a b c ..." -> n doubles.
bool parse_numbers(const std::string& s, double* out, int n) {
  const char* p = s.c_str();
  for (int i = 0; i < n; ++i) {
    char* end = nullptr;
    out[i] = std::strtod(p, &end);
    if (end == p) return false;
    p = end;
  }
  while (*p == ' ') ++p;
  return *p == '\0';
}

}  // namespace

LogSkip to_skip(DecodeStatus s) {
  switch (s) {
    case DecodeStatus::WrongFingerprint: return LogSkip::WrongFingerprint;
    case DecodeStatus::AbsurdSize: return LogSkip::AbsurdSize;
    default: return LogSkip::Undecodable;
  }
}

DecodeStatus check_image_t(const uint8_t* data, size_t n, std::string& why) {
  if (n < 8) {
    why = "payload of " + std::to_string(n) + " bytes is shorter than a fingerprint";
    return DecodeStatus::Undecodable;
  }
  int64_t hash = 0;
  for (int i = 0; i < 8; ++i) hash = static_cast<int64_t>(static_cast<uint64_t>(hash) << 8 | data[i]);
  if (hash != bot_core::image_t::getHash()) {
    why = "not a bot_core.image_t";
    return DecodeStatus::WrongFingerprint;
  }
  // Every length against the payload: a metadata count can claim no more entries than the
  // bytes that follow hold, so the decoder's allocations stay within a few times the payload.
  const LayoutStatus st = check_layout<bot_core::image_t>(data, n, why);
  if (st != LayoutStatus::Fits) return st == LayoutStatus::BadLength ? DecodeStatus::AbsurdSize : DecodeStatus::Undecodable;
  return DecodeStatus::Ok;
}

namespace {

// A time from the message as nanoseconds, through rsd's one check for times from outside
// (dsp::Stamp): nothing for one beyond its window.
bool us_to_ns(int64_t us, int64_t& ns) {
  const std::optional<dsp::Stamp> s = dsp::Stamp::from_us(us);
  if (s) ns = s->ns();
  return s.has_value();
}

// The first row's time (monotonic), the Unix time and the sequence.
bool parse_times(const bot_core::image_t& img, RecordedFrame& out, std::string& why) {
  int64_t ns = 0, us = img.utime;
  if (!us_to_ns(img.utime, out.meta.wall_ns))  // libbot2's convention; older rsd logs: their monotonic time
    return why = "utime " + std::to_string(img.utime) + " is out of range", false;
  if (parse_number(value_of(img, "frame_ns"), ns)) {
    const std::optional<dsp::Stamp> s = dsp::Stamp::from_ns(ns);
    if (!s) return why = "metadata frame_ns " + std::to_string(ns) + " is out of range", false;
    out.meta.first_row_ns = s->ns();
  } else if (parse_number(value_of(img, "frame_utime"), us)) {
    if (!us_to_ns(us, out.meta.first_row_ns)) return why = "metadata frame_utime " + std::to_string(us) + " is out of range", false;
  } else {
    out.meta.first_row_ns = out.meta.wall_ns;
  }
  uint64_t seq = 0;
  if (parse_number(value_of(img, "sequence"), seq)) out.meta.sequence = seq;
  return true;
}

// Exposure, readout, line delay, frame rate and first row, each checked for range: a NaN or
// absurd value here would stamp every row of the frame wrong.
bool parse_timing(const bot_core::image_t& img, RecordedFrame& out, std::string& why) {
  auto bad = [&](const char* key, double v) { return why = std::string("metadata ") + key + " " + number_text(v) + " is out of range", false; };
  double x = 0;
  if (parse_number(value_of(img, "exposure_s"), x)) out.meta.exposure_s = x;
  else if (parse_number(value_of(img, "exposure_ns"), x)) out.meta.exposure_s = x * 1e-9;
  if (!dsp::limits::kExposureS.contains(out.meta.exposure_s)) return bad("exposure", out.meta.exposure_s);
  dsp::Readout r;
  if (dsp::parse_readout(value_of(img, "readout"), r)) out.readout = r;
  double t[4];
  if (parse_numbers(value_of(img, "timing"), t, 4)) {
    if (!dsp::limits::kLineDelayS.contains(t[0])) return bad("timing (line delay)", t[0]);
    if (!dsp::limits::kFrameRateHz.contains(t[1])) return bad("timing (frame rate)", t[1]);
    // -1: the readout's natural first row (dsp::RowTiming::first_row)
    if (!(t[3] >= -1 && t[3] < img.height && t[3] == std::floor(t[3]))) return bad("timing (first row)", t[3]);
    out.line_delay_s = t[0];
    out.frame_rate_hz = t[1];
    out.first_row = static_cast<int>(t[3]);
  } else if (parse_number(value_of(img, "line_delay_ns"), x)) {
    if (!(x >= 0 && x < 1e9)) return bad("line_delay_ns", x);
    out.line_delay_s = x * 1e-9;
  }
  return true;
}

// "fx fy cx cy k1 k2 p1 p2 k3" (a pinhole-radtan lens), or those, k4 and the lens's name
// ("... k3 k4 pinhole-equi"): the Distortion's terms in their order, each slot meaning the same.
bool parse_intrinsics(const bot_core::image_t& img, RecordedFrame& out, std::string& why) {
  double k[10] = {};
  dsp::LensModel lens = dsp::LensModel::PinholeRadtan;
  const std::string text = value_of(img, "intrinsics");
  if (!parse_numbers(text, k, 9)) {
    const size_t name = text.find_last_of(' ');
    const auto model = name == std::string::npos ? std::nullopt : dsp::parse_lens_model(text.substr(name + 1));
    if (!model || !parse_numbers(text.substr(0, name), k, 10)) return true;  // none of rsd's: no intrinsics
    lens = *model;
  }
  for (double v : k)
    if (!std::isfinite(v)) return why = "metadata intrinsics hold a value that is not finite", false;
  if (!(k[0] > 0 && k[1] > 0)) return why = "metadata intrinsics have a focal length that is not positive", false;
  dsp::CameraModel c;
  c.width = img.width, c.height = img.height;
  c.fx = k[0], c.fy = k[1], c.cx = k[2], c.cy = k[3];
  c.dist = {k[4], k[5], k[6], k[7], k[8], k[9], lens};
  if (const dsp::CameraOutOfRange r = dsp::out_of_range(c); r.part != dsp::CameraOutOfRange::None)
    return why = "metadata intrinsics: " + r.why, false;
  out.camera = c;
  return true;
}

}  // namespace

bool parse_frame(const bot_core::image_t& img, RecordedFrame& out, std::string& why) {
  const auto fmt = pixel_format(img.pixelformat);
  if (!fmt)
    return why = "pixelformat " + std::to_string(img.pixelformat) + " is none of rsd's (" + dsp::format_names() + ")", false;
  if (!dsp::limits::side_ok(img.width) || !dsp::limits::side_ok(img.height))
    return why = "size " + std::to_string(img.width) + "x" + std::to_string(img.height) + " (sides must be " + dsp::limits::kSide.text + ")", false;
  if (std::string fit; !dsp::size_fits(*fmt, img.width, img.height, &fit)) return why = "width, height: " + fit, false;
  const int64_t row = static_cast<int64_t>(dsp::row_bytes(*fmt, img.width));
  if (*fmt == dsp::PixelFormat::I420 && img.row_stride % 2) return why = "row_stride " + std::to_string(img.row_stride) + " is odd (i420)", false;
  if (img.row_stride < row ||
      img.data.size() < dsp::buffer_bytes(*fmt, img.width, img.height, static_cast<size_t>(img.row_stride)))
    return why = "row stride " + std::to_string(img.row_stride) + " and " + std::to_string(img.data.size()) +
                 " bytes do not hold " + std::to_string(img.width) + "x" + std::to_string(img.height) + " pixels", false;
  out = {};
  out.format = {img.width, img.height, *fmt};
  return parse_times(img, out, why) && parse_timing(img, out, why) && parse_intrinsics(img, out, why);
}

DecodeStatus decode_frame(const uint8_t* data, size_t n, bot_core::image_t& img, RecordedFrame& out, std::string& why) {
  DecodeStatus st = check_image_t(data, n, why);
  if (st == DecodeStatus::Ok) st = decode_checked(data, n, img, why);
  if (st == DecodeStatus::Ok && !parse_frame(img, out, why)) st = DecodeStatus::Undecodable;
  return st;
}

void preallocate(bot_core::image_t& img, const FrameFormat& fmt, std::initializer_list<const char*> keys, size_t capacity) {
  img.width = fmt.width;
  img.height = fmt.height;
  img.row_stride = static_cast<int32_t>(dsp::row_bytes(fmt.format, fmt.width));
  img.pixelformat = fourcc(fmt.format);
  img.size = static_cast<int32_t>(fmt.bytes());
  img.data.resize(fmt.bytes());
  img.nmetadata = static_cast<int32_t>(keys.size());
  img.metadata.resize(keys.size());
  size_t i = 0;
  for (const char* k : keys) {
    img.metadata[i].key = k;
    img.metadata[i++].value.reserve(capacity);
  }
}

void copy_pixels(const bot_core::image_t& img, const dsp::ImageView& dst) {
  dsp::copy_image(img.data.data(), img.row_stride, dst);
}

dsp::RowTiming row_timing(const RecordedFrame& f, double fallback_fps) {
  dsp::RowTiming t = dsp::RowTiming::full_frame(f.format.height, f.frame_rate_hz.value_or(fallback_fps),
                                                f.readout.value_or(dsp::Readout::TopToBottom));
  if (f.line_delay_s && *f.line_delay_s > 0) t.line_delay_s = *f.line_delay_s;
  t.exposure_s = f.meta.exposure_s;
  t.first_row = f.first_row;
  return t;
}

RawFrameEncoder::RawFrameEncoder(const FrameFormat& fmt, const dsp::RowTiming& timing,
                                 const std::optional<dsp::CameraModel>& camera)
    : timing_(timing) {
  preallocate(msg_, fmt, kKeys, kValueCapacity);
  char text[kValueCapacity];
  set(2, dsp::to_string(timing.readout).data());
  set(5, "0");
  std::snprintf(text, sizeof text, "%.17g", timing.line_delay_s * 1e9);
  set(1, text);
  std::snprintf(text, sizeof text, "%.17g %.17g %.17g %d", timing.line_delay_s, timing.frame_rate_hz, timing.exposure_s,
                timing.first_row);
  set(8, text);
  if (camera) {
    const dsp::CameraModel& c = *camera;
    if (c.dist.model == dsp::LensModel::PinholeRadtan)
      std::snprintf(text, sizeof text, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g", c.fx, c.fy, c.cx, c.cy,
                    c.dist.k1, c.dist.k2, c.dist.p1, c.dist.p2, c.dist.k3);
    else
      std::snprintf(text, sizeof text, "%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %s", c.fx, c.fy, c.cx,
                    c.cy, c.dist.k1, c.dist.k2, c.dist.p1, c.dist.p2, c.dist.k3, c.dist.k4, dsp::lens_model_name(c.dist.model));
    set(9, text);
  } else {  // no intrinsics known: leave the key out
    msg_.metadata.pop_back();
    msg_.nmetadata = static_cast<int32_t>(msg_.metadata.size());
  }
  buf_.resize(static_cast<size_t>(msg_.getEncodedSize()) + 16 * kValueCapacity);
}

void RawFrameEncoder::set(size_t index, const char* text) {
  auto& v = msg_.metadata[index].value;
  const size_t n = std::min(std::strlen(text), kValueCapacity);
  v.assign(text, text + n);  // within the reserved capacity: no allocation
  msg_.metadata[index].n = static_cast<int32_t>(n);
}

size_t RawFrameEncoder::encode(const dsp::ImageView& img, const FrameMeta& meta) {
  msg_.utime = (meta.wall_ns ? meta.wall_ns : meta.first_row_ns) / 1000;
  dsp::copy_image(img, {msg_.data.data(), img.width, img.height, msg_.row_stride, img.format});
  char text[64];
  std::snprintf(text, sizeof text, "%" PRId64, meta.first_row_ns / 1000);
  set(0, text);
  std::snprintf(text, sizeof text, "%.17g", meta.exposure_s * 1e9);
  set(3, text);
  std::snprintf(text, sizeof text, "%" PRIu64, meta.sequence);
  set(4, text);
  std::snprintf(text, sizeof text, "%" PRId64, meta.first_row_ns);
  set(6, text);
  std::snprintf(text, sizeof text, "%.17g", meta.exposure_s);
  set(7, text);
  const int len = msg_.encode(buf_.data(), 0, static_cast<int>(buf_.size()));
  size_ = len > 0 ? static_cast<size_t>(len) : 0;
  return size_;
}

}  // namespace rsd::formats
