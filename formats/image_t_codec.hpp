// Raw frames as recorded in LCM logs (bot_core.image_t on RSD_RAW), both ways, and checked
// decoding of the LCM messages rsd reads from logs or the network.
//
// Metadata keys of a raw frame. The documented ones (lcmtypes/bot_core_image_t.lcm), which
// rsd-sim logs and rsd's RSD_RAW also carry:
//   frame_utime, line_delay_ns, readout, exposure_ns, sequence, rectified
// and the exact ones rsd --record adds so that a replay reproduces the live run bit for bit
// (every double printed with 17 significant digits, which reads back to the same double):
//   frame_ns     first row's capture time, ns (the documented frame_utime rounds to us)
//   exposure_s   the frame's row exposure, s
//   timing       "line_delay_s frame_rate_hz exposure_s first_row" of the sensor
//   intrinsics   "fx fy cx cy k1 k2 p1 p2 k3" of the camera
// A reader prefers the exact keys and falls back to the documented ones.
#pragma once

#include <bot_core/image_t.hpp>

#include <array>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "dsp/core/frame.hpp"
#include "dsp/geometry/row_timing.hpp"
#include "formats/lcm_layout_check.hpp"
#include "formats/lcm_log.hpp"
#include "dsp/geometry/camera_model.hpp"

namespace rsd::formats {

using dsp::FrameFormat;
using dsp::FrameMeta;

// bot_core.image_t pixel formats (libbot2's FourCC codes) of the frames rsd reads and writes:
// GRAY, LE_GRAY16, RGB, YUYV, NV12, I420 (YUV420 is read as I420 too), BAYER_* and
// LE_BAYER16_*.
int32_t fourcc(dsp::PixelFormat f);
std::optional<dsp::PixelFormat> pixel_format(int32_t fourcc_code);

// What a raw frame's header and metadata say.
struct RecordedFrame {
  FrameFormat format;
  FrameMeta meta;                 // first_row_ns, sequence, exposure_s
  std::optional<dsp::Readout> readout;
  std::optional<double> line_delay_s;
  std::optional<double> frame_rate_hz;  // only in rsd's own recordings
  int first_row = -1;
  std::optional<dsp::CameraModel> camera;  // only in rsd's own recordings
};

enum class DecodeStatus { Ok, WrongFingerprint, AbsurdSize, Undecodable };
LogSkip to_skip(DecodeStatus s);

// Checks a bot_core.image_t payload before decoding it: fingerprint, then every length field
// against the payload (check_layout; lcm-gen's decoder would otherwise allocate whatever a
// corrupt `size` says). `why` explains a failure.
DecodeStatus check_image_t(const uint8_t* data, size_t n, std::string& why);

// Fingerprint check, layout check (formats/lcm_layout_check.hpp), then decode: for every type
// in lcmtypes/.
template <class Msg>
DecodeStatus decode_checked(const uint8_t* data, size_t n, Msg& msg, std::string& why) {
  if (n < 8) {
    why = "payload of " + std::to_string(n) + " bytes is shorter than a fingerprint";
    return DecodeStatus::Undecodable;
  }
  int64_t hash = 0;
  for (int i = 0; i < 8; ++i) hash = static_cast<int64_t>(static_cast<uint64_t>(hash) << 8 | data[i]);
  if (hash != Msg::getHash()) {
    why = std::string("not a ") + Msg::getTypeName();
    return DecodeStatus::WrongFingerprint;
  }
  // Every string and array length of every type, before lcm-gen's decoder believes it.
  if (const LayoutStatus st = check_layout<Msg>(data, n, why); st != LayoutStatus::Fits)
    return st == LayoutStatus::BadLength ? DecodeStatus::AbsurdSize : DecodeStatus::Undecodable;
  if (n > static_cast<size_t>(std::numeric_limits<int>::max()) || msg.decode(data, 0, static_cast<int>(n)) < 0) {
    why = std::string("does not decode as ") + Msg::getTypeName();
    return DecodeStatus::Undecodable;
  }
  return DecodeStatus::Ok;
}

// A decoded image_t's size, format and metadata; false (with `why`) when inconsistent.
bool parse_frame(const bot_core::image_t& img, RecordedFrame& out, std::string& why);

// The one way rsd reads a raw frame from bytes (a log event, an LCM message): check_image_t,
// decode_checked, then parse_frame. Not Ok: `why` explains, and parse_frame's complaints
// count as Undecodable. `img` is reused between calls (no allocation once large enough).
// The timestamp rule is parse_frame's: frame_ns, else frame_utime, else the message's utime.
DecodeStatus decode_frame(const uint8_t* data, size_t n, bot_core::image_t& img, RecordedFrame& out, std::string& why);

// Sizes a message once for frames of `fmt`, with metadata slots named `keys` whose values
// have room for `capacity` bytes: filling and encoding it per frame then allocates nothing.
void preallocate(bot_core::image_t& img, const FrameFormat& fmt, std::initializer_list<const char*> keys, size_t capacity);

// Copies the pixels into dst (same size and format as the frame).
void copy_pixels(const bot_core::image_t& img, const dsp::ImageView& dst);

// The sensor timing a recorded frame describes; fields it does not carry come from
// `fallback_fps` (frame rate) and the documented defaults.
dsp::RowTiming row_timing(const RecordedFrame& f, double fallback_fps);

// Encodes raw frames as rsd --record writes them, from a message and a buffer sized once:
// no heap allocation per frame.
class RawFrameEncoder {
 public:
  RawFrameEncoder(const FrameFormat& fmt, const dsp::RowTiming& timing, const std::optional<dsp::CameraModel>& camera);
  // Encodes the frame; returns its size (0 on failure). data() is valid until the next call.
  size_t encode(const dsp::ImageView& img, const FrameMeta& meta);
  const uint8_t* data() const { return buf_.data(); }
  size_t size() const { return size_; }

 private:
  void set(size_t index, const char* text);
  bot_core::image_t msg_;
  std::vector<uint8_t> buf_;
  size_t size_ = 0;
  dsp::RowTiming timing_;
};

}  // namespace rsd::formats
