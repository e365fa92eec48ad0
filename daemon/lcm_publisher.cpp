#include "daemon/lcm_publisher.hpp"

#include "drivers/lcm_connect.hpp"
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
    : url_(url), ch_(std::move(channels)) {
  std::string why;
  lcm_ = drivers::create_lcm(url, why);
  if (!lcm_)
    throw std::runtime_error("lcm: cannot open '" + url + "'" + (why.empty() ? " (use memq://, tcpq://127.0.0.1:PORT or file:///path.lcmlog?mode=w)" : ": " + why));
  // Everything sized once, for the largest message we will send.
  formats::preallocate(image_, fmt, kMetaKeys, kMetaValueCapacity);
  info_.unrectified_reason.reserve(128);
  health_.source.reserve(64);
  health_.source_state.reserve(64);
  buf_.resize(static_cast<size_t>(image_.getEncodedSize()) + 4096);
  health_buf_.resize(4096);
}

// lcm_destroy unsubscribes the velocity input's channels, reconnecting a lost tcpq instance:
// drivers::destroy_lcm never lets that wait for a silent hub.
LcmPublisher::~LcmPublisher() { drivers::destroy_lcm(lcm_, url_); }

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
  if (!hub_ready()) return;  // lost with the hub, as LCM loses what it cannot send
  lcm_publish(lcm_, channel, data, static_cast<unsigned>(size));
}

// A tcpq instance that lost its hub reconnects inside lcm_publish, waiting for the hub's answer
// without a timeout: asked first (drivers/lcm_connect), at most once a second, so that neither
// a silent hub nor asking it holds the publishing thread for more than a moment at a time.
bool LcmPublisher::hub_ready() {
  if (!drivers::lost_tcpq_hub(lcm_, url_)) return true;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_probe_ < std::chrono::seconds(1)) return false;
  last_probe_ = now;
  return drivers::probe_tcpq_hub(url_, kHubProbeMs).safe_to_connect();
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
