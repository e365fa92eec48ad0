#include "daemon/lcm_publisher.hpp"

#include "dsp/core/image_planes.hpp"
#include "formats/image_t_codec.hpp"

#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace rsd::daemon {

namespace {

constexpr std::initializer_list<const char*> kMetaKeys = {"frame_utime", "line_delay_ns", "readout", "exposure_ns", "sequence", "rectified"};
constexpr size_t kMetaValueCapacity = 32;

}  // namespace

LcmPublisher::LcmPublisher(const std::string& url, Channels channels, const drivers::FrameFormat& fmt)
    : lcm_(lcm_create(url.c_str())), ch_(std::move(channels)) {
  if (!lcm_) throw std::runtime_error("lcm: cannot open '" + url + "' (use memq:// or file:///path.lcmlog?mode=w)");
  // Everything sized once, for the largest message we will send.
  formats::preallocate(image_, fmt, kMetaKeys, kMetaValueCapacity);
  info_.unrectified_reason.reserve(128);
  health_.source.reserve(64);
  health_.source_state.reserve(64);
  buf_.resize(static_cast<size_t>(image_.getEncodedSize()) + 4096);
  health_buf_.resize(4096);
}

LcmPublisher::~LcmPublisher() { lcm_destroy(lcm_); }

void LcmPublisher::set_meta(size_t index, const char* text) {
  auto& v = image_.metadata[index].value;
  const size_t n = std::min(std::strlen(text), kMetaValueCapacity);
  v.assign(text, text + n);  // within the reserved capacity: no allocation
  image_.metadata[index].n = static_cast<int32_t>(n);
}

template <class Msg>
void LcmPublisher::publish(const std::string& channel, const Msg& msg, std::vector<uint8_t>& buf, bool record) {
  const int len = msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  if (len <= 0) return;
  send(channel.c_str(), buf.data(), static_cast<size_t>(len));
  if (record && record_) record_->write(channel.c_str(), formats::wall_clock_us(), buf.data(), static_cast<size_t>(len));
}

void LcmPublisher::send(const char* channel, const void* data, size_t size) {
  std::lock_guard lock(publish_mutex_);
  lcm_publish(lcm_, channel, data, static_cast<unsigned>(size));
}

void LcmPublisher::publish_encoded(const std::string& channel, const void* data, size_t size) {
  send(channel.c_str(), data, size);
  if (record_) record_->write(channel.c_str(), formats::wall_clock_us(), data, size);
}

void LcmPublisher::publish_image(bool raw, const dsp::ImageView& img, const ImageStamp& s) {
  image_.utime = s.utime;
  dsp::copy_image(img, {image_.data.data(), img.width, img.height, image_.row_stride, img.format});
  char text[kMetaValueCapacity];
  std::snprintf(text, sizeof text, "%" PRId64, s.frame_utime);
  set_meta(0, text);
  std::snprintf(text, sizeof text, "%.17g", s.line_delay_s * 1e9);
  set_meta(1, text);
  set_meta(2, dsp::to_string(s.readout).data());
  std::snprintf(text, sizeof text, "%.17g", s.exposure_s * 1e9);
  set_meta(3, text);
  std::snprintf(text, sizeof text, "%" PRId64, s.sequence);
  set_meta(4, text);
  set_meta(5, s.rectified ? "1" : "0");
  publish(raw ? ch_.raw : ch_.image, image_, buf_, !raw);  // raw frames are recorded at capture
}

void LcmPublisher::publish_info() { publish(ch_.info, info_, buf_); }
void LcmPublisher::publish_health() { publish(ch_.health, health_, health_buf_); }

}  // namespace rsd::daemon
