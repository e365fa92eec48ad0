#include "drivers/lcm_source.hpp"

#include "dsp/core/image_planes.hpp"
#include <cmath>
#include <cstdio>
#include <cstring>

#include <spdlog/spdlog.h>

#include "drivers/lcm_connect.hpp"
#include "drivers/lcm_receive.hpp"
#include "drivers/monotonic_clock.hpp"  // monotonic_ns

namespace rsd::drivers {

LcmSource::LcmSource(LcmSourceConfig cfg) : cfg_(std::move(cfg)) {}

LcmSource::~LcmSource() { close_lcm(); }

// Unsubscribing before lcm_destroy: liblcm's tcpq provider frees a channel's name only when it is
// unsubscribed (lcm_destroy leaves them allocated, which LeakSanitizer reports). On an instance
// that lost its hub, unsubscribing reconnects: never to a hub that would not answer (then
// drivers::destroy_lcm closes the instance in the background, and this thread goes on).
void LcmSource::close_lcm() {
  if (!lcm_) return;
  const bool may = may_reconnect(lcm_, cfg_.url);
  for (lcm_subscription_t*& s : subs_) {
    if (s && may) lcm_unsubscribe(lcm_, s);
    s = nullptr;
  }
  if (may) lcm_destroy(lcm_);
  else destroy_lcm_detached(lcm_, cfg_.url);  // the hub was asked just now
  lcm_ = nullptr;
}

// The first three skips of a reason are logged each, later ones at every tenfold.
void LcmSource::skip(formats::LogSkip r, const std::string& detail) {
  const uint64_t n = skips_[static_cast<size_t>(r)].fetch_add(1, std::memory_order_relaxed) + 1;
  if (skip_log_[static_cast<size_t>(r)].due(n) || n <= 3)
    spdlog::warn("lcm source {}: message skipped: {}: {}{}", cfg_.url, to_string(r), detail,
                 n > 3 ? " (" + std::to_string(n) + " skipped for this reason so far)" : "");
}

uint64_t LcmSource::refused() const {
  uint64_t n = 0;
  for (const auto& k : skips_) n += k.load(std::memory_order_relaxed);
  return n;
}

void LcmSource::open() {
  if (!lcm_) {
    if (cfg_.url.rfind("udpm://", 0) == 0 && !cfg_.allow_multicast)
      throw std::runtime_error("lcm source: '" + cfg_.url + "' is multicast; set allow_multicast: true to use it");
    // Kept across reopen attempts: messages that arrive meanwhile wait in LCM's queue.
    std::string why;
    lcm_ = create_lcm(cfg_.url, why);
    if (!lcm_) throw CameraError("lcm source: cannot open '" + cfg_.url + "'" + (why.empty() ? "" : ": " + why));
    // tcpq:// hands out an instance even when its hub is down, with no descriptor to wait on.
    if (lcm_get_fileno(lcm_) < 0) {
      close_lcm();
      throw CameraError("lcm source: cannot connect to '" + cfg_.url + "'");
    }
    line_.reset();  // a new connection is a new stream (a player started again)
    subs_[0] = lcm_subscribe(lcm_, cfg_.channel.c_str(), &LcmSource::on_image, this);
    subs_[1] = lcm_subscribe(lcm_, cfg_.velocity_channel.c_str(), &LcmSource::on_velocity, this);
    if (!pose_channel_.empty()) subs_[2] = lcm_subscribe(lcm_, pose_channel_.c_str(), &LcmSource::on_pose, this);
  }
  if (first_.format.width > 0) return;  // reopened after a loss: the format is known
  opening_ = true;
  got_frame_ = false;
  early_velocity_.clear();
  early_pose_.clear();
  const int64_t until = monotonic_ns() + static_cast<int64_t>(cfg_.open_timeout_s * 1e9);
  bool lost = false;
  while (!got_frame_ && monotonic_ns() < until)
    if (handle_lcm(lcm_, 100) < 0) {
      lost = true;
      break;
    }
  opening_ = false;
  // A lost connection (a hub gone, a peer's partial message) is not re-established by LCM: the
  // next attempt builds a new instance.
  if (!got_frame_ && lost && cfg_.url.rfind("file://", 0) != 0) close_lcm();
  if (!got_frame_)
    throw CameraError("lcm source: no frame on '" + cfg_.channel + "' at " + cfg_.url + " within " +
                      std::to_string(cfg_.open_timeout_s) + " s");
  timing_ = row_timing(first_, cfg_.fallback_fps);
}

void LcmSource::on_image(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
  auto* self = static_cast<LcmSource*>(user);
  const auto* data = static_cast<const uint8_t*>(rbuf->data);
  const formats::DecodeStatus st = formats::decode_frame(data, rbuf->data_size, self->img_, self->frame_, self->why_);
  if (st != formats::DecodeStatus::Ok) return self->skip(formats::to_skip(st), std::string(channel) + ": " + self->why_);
  // A frame must continue the stream's time line: a repeated or backward stamp would make the
  // pipeline's row times (and the velocity it looks up) go back, and one wild stamp taken as
  // the newest would make every later frame "out of order".
  const int64_t newest = self->line_.newest();
  if (self->line_.offer(self->frame_.meta.first_row_ns) == dsp::TimeLine::Verdict::Held)
    return self->skip(formats::LogSkip::OutOfOrder, std::string(channel) + ": first row at " +
                                                        std::to_string(self->frame_.meta.first_row_ns) +
                                                        " ns, off the stream's time line (newest " + std::to_string(newest) + " ns)");
  if (self->opening_) {
    self->first_ = self->frame_;
    const FrameFormat& f = self->first_.format;
    self->pending_image_ = dsp::Image(f.width, f.height, f.format);
    formats::copy_pixels(self->img_, self->pending_image_.view());
    self->pending_meta_ = self->frame_.meta;
    self->pending_ = self->got_frame_ = true;
    return;
  }
  const FrameFormat& f = self->frame_.format;
  if (!self->target_ || f.width != self->first_.format.width || f.height != self->first_.format.height ||
      f.format != self->first_.format.format)
    return self->skip(formats::LogSkip::Undecodable, std::string(channel) + ": frame size or format changed");
  formats::copy_pixels(self->img_, *self->target_);
  *self->target_meta_ = self->frame_.meta;
  self->got_frame_ = true;
}

void LcmSource::on_velocity(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
  auto* self = static_cast<LcmSource*>(user);
  rsd::velocity_t m;
  const formats::DecodeStatus st = formats::decode_checked(static_cast<const uint8_t*>(rbuf->data), rbuf->data_size, m, self->why_);
  if (st != formats::DecodeStatus::Ok) return self->skip(formats::to_skip(st), std::string(channel) + ": " + self->why_);
  // Before the first frame the daemon has not connected its sink yet: keep them (bounded).
  if (self->opening_ || self->pending_) {
    if (self->early_velocity_.size() < 4096) self->early_velocity_.push_back(m);
    return;
  }
  self->deliver_velocity(m);
}

void LcmSource::on_pose(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
  auto* self = static_cast<LcmSource*>(user);
  bot_core::pose_t m;
  const formats::DecodeStatus st = formats::decode_checked(static_cast<const uint8_t*>(rbuf->data), rbuf->data_size, m, self->why_);
  if (st != formats::DecodeStatus::Ok) return self->skip(formats::to_skip(st), std::string(channel) + ": " + self->why_);
  // Before the first frame only the newest matters for a 0.1 s velocity window: keep few.
  if (self->opening_ || self->pending_) {
    if (self->early_pose_.size() < 4096) self->early_pose_.push_back(m);
    return;
  }
  self->deliver_pose(m);
}

CaptureStatus LcmSource::capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) {
  if (pending_) {  // the frame open() received, after the velocity that came before it
    pending_ = false;
    for (const auto& v : early_velocity_) deliver_velocity(v);
    for (const auto& p : early_pose_) deliver_pose(p);
    early_velocity_.clear();
    early_pose_.clear();
    const dsp::ImageView src = pending_image_.view();
    dsp::copy_image(src, dst);
    meta = pending_meta_;
    return CaptureStatus::Frame;
  }
  target_ = &dst;
  target_meta_ = &meta;
  got_frame_ = false;
  const int64_t until = monotonic_ns() + std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count();
  // One message per lcm_handle: the velocity before a frame is delivered before it.
  while (!got_frame_) {
    const int64_t left_ms = (until - monotonic_ns()) / 1000000;
    if (left_ms <= 0) break;
    if (handle_lcm(lcm_, static_cast<int>(left_ms)) < 0) {
      // A log being read has ended (file:// provider), or the connection failed.
      target_ = nullptr;
      if (cfg_.url.rfind("file://", 0) == 0) return CaptureStatus::EndOfStream;
      // A failed tcpq connection is not re-established by LCM (its descriptor stays -1, and
      // handling it again aborts in FD_SET): the reconnect builds a new instance (open()).
      close_lcm();
      throw CameraError("lcm source: " + cfg_.url + " stopped delivering");
    }
  }
  target_ = nullptr;
  return got_frame_ ? CaptureStatus::Frame : CaptureStatus::Timeout;
}

}  // namespace rsd::drivers
