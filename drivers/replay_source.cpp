#include "drivers/replay_source.hpp"

#include <cstdio>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <spdlog/spdlog.h>

#include "drivers/monotonic_clock.hpp"  // monotonic_ns
#include "dsp/core/input_limits.hpp"
#include "dsp/core/stamp.hpp"

namespace rsd::drivers {

bool ReplayPacer::wait(int64_t log_us, std::chrono::milliseconds timeout) {
  if (speed_ <= 0) return true;
  const int64_t now = monotonic_ns();
  const dsp::TimeLine::Verdict v = line_.offer(log_us);
  if (v == dsp::TimeLine::Verdict::Held) return true;
  if (!started_ || v == dsp::TimeLine::Verdict::Replaces) {
    started_ = true;
    log0_us_ = log_us;
    wall0_ns_ = now;
    return true;
  }
  // Log times lie within rsd's window (the replay refuses others), so their difference fits; a
  // slow speed's quotient is clamped to +-1e18 ns (31 years) before it is an integer again, and a
  // monotonic clock's wall0 (years of uptime at most) added to it fits too.
  const double ahead_ns = std::clamp(static_cast<double>(log_us - log0_us_) * 1000.0 / speed_, -1e18, 1e18);
  const int64_t due = wall0_ns_ + static_cast<int64_t>(ahead_ns);
  const int64_t limit = std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count();
  if (due - now > limit) {
    std::this_thread::sleep_for(timeout);
    return false;
  }
  if (due > now) std::this_thread::sleep_for(std::chrono::nanoseconds(due - now));
  return true;
}

bool parse_speed(const std::string& text, double& speed) {
  if (text == "fast" || text == "max") return speed = 0, true;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !(v > 0) || !std::isfinite(v)) return false;
  speed = v;
  return true;
}

ReplaySource::ReplaySource(ReplayConfig cfg) : cfg_(std::move(cfg)), pacer_(cfg_.speed) {}

bool ReplaySource::ignored_channel(const std::string& c) const {
  return std::find(cfg_.ignore.begin(), cfg_.ignore.end(), c) != cfg_.ignore.end();
}

void ReplaySource::open() {
  // A separate, silent reader finds the first usable frame (and the second, for the frame
  // rate of logs that do not record it); the replay's own reader reports what it skips.
  formats::LcmLogReader probe(cfg_.file);
  probe.set_message_handler({});
  formats::LogEvent ev;
  std::optional<formats::RecordedFrame> first, second;
  uint64_t events = 0;
  while ((!first || (!first->frame_rate_hz && !second)) && probe.next(ev)) {
    ++events;
    if (ev.channel != cfg_.channel) continue;
    std::string why;
    formats::RecordedFrame f;
    if (formats::decode_frame(ev.data.data(), ev.data.size(), img_, f, why) != formats::DecodeStatus::Ok) continue;
    (first ? second : first) = f;
  }
  if (!first)
    throw std::runtime_error(cfg_.file + ": no usable raw frame (bot_core.image_t) on channel '" + cfg_.channel + "' in " +
                             std::to_string(events) + " events" +
                             (probe.skipped_total() ? "; skipped " + probe.skip_summary() : std::string()));
  first_ = *first;
  double fps = cfg_.fallback_fps;
  if (second && second->meta.first_row_ns > first->meta.first_row_ns)
    fps = 1e9 / static_cast<double>(second->meta.first_row_ns - first->meta.first_row_ns);
  if (!dsp::limits::kFrameRateHz.contains(fps)) fps = cfg_.fallback_fps;  // two frames years apart: no rate
  timing_ = row_timing(first_, fps);
  reader_ = std::make_unique<formats::LcmLogReader>(cfg_.file);
  if (cfg_.quiet_skips) reader_->set_message_handler({});
}

void ReplaySource::start() {
  reader_->rewind();
  pacer_.reset();
  pending_ = false;
  frames_this_pass_ = 0;
}

std::string ReplaySource::summary(double seconds) const {
  const ReplaySource& r = *this;
  char text[512];
  std::snprintf(text, sizeof text, "replayed %llu frames from %s in %.2f s (%.1f fps), %llu velocity messages",
                static_cast<unsigned long long>(r.frames()), r.config().file.c_str(), seconds,
                seconds > 0 ? static_cast<double>(r.frames()) / seconds : 0.0,
                static_cast<unsigned long long>(r.velocity_messages()));
  std::string s = text;
  if (r.ignored()) s += ", " + std::to_string(r.ignored()) + " recorded outputs ignored";
  if (r.passes()) s += ", looped " + std::to_string(r.passes()) + " times";
  const formats::LcmLogReader* rd = r.reader();
  if (rd && rd->skipped_total()) s += "; skipped " + std::to_string(rd->skipped_total()) + " events: " + rd->skip_summary();
  else s += "; nothing skipped";
  return s;
}

double ReplaySource::progress() const {
  if (!reader_ || reader_->size() == 0) return 0;
  return std::min(1.0, static_cast<double>(position_.load(std::memory_order_relaxed)) / static_cast<double>(reader_->size()));
}

CaptureStatus ReplaySource::capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) {
  for (;;) {
    if (!pending_) {
      if (!reader_->next(ev_)) {
        if (!cfg_.loop || frames_this_pass_ == 0) return CaptureStatus::EndOfStream;
        // Again from the start, later by the log's length plus one frame period, so that
        // frame and velocity times keep increasing: while they stay in rsd's window for times
        // (the log's own times do; passes add up), else the play ends there.
        if (!next_pass_offsets()) return CaptureStatus::EndOfStream;
        reader_->rewind();
        frames_this_pass_ = 0;
        ++passes_;
        continue;
      }
      if (!dsp::Stamp::from_us(ev_.timestamp_us)) {  // before any arithmetic on it
        reader_->skip(formats::LogSkip::Undecodable, ev_.offset,
                      "event time " + std::to_string(ev_.timestamp_us) + " us is out of range");
        continue;
      }
      pending_ = true;
      position_.store(reader_->position(), std::memory_order_relaxed);
      if (frames_ == 0 && passes_ == 0 && first_ts_us_ == 0) first_ts_us_ = ev_.timestamp_us;
      last_ts_us_ = std::max(last_ts_us_, ev_.timestamp_us);
    }
    const bool frame = ev_.channel == cfg_.channel, velocity = ev_.channel == cfg_.velocity_channel;
    const bool pose = !pose_channel_.empty() && ev_.channel == pose_channel_;
    if ((frame || velocity || pose) && !pacer_.wait(ev_.timestamp_us + ts_offset_us_, timeout)) return CaptureStatus::Timeout;
    pending_ = false;
    if (frame) {
      if (take_frame(dst, meta)) return CaptureStatus::Frame;
    } else if (velocity) {
      take_velocity();
    } else if (pose) {
      take_pose();
    } else if (ignored_channel(ev_.channel)) {
      ++ignored_;
    } else {
      reader_->skip(formats::LogSkip::UnknownChannel, ev_.offset, "channel '" + ev_.channel + "'");
    }
  }
}

bool ReplaySource::next_pass_offsets() {
  const int64_t frame_ns = last_frame_ns_ - first_frame_ns_ + static_cast<int64_t>(1e9 / timing_.frame_rate_hz);
  const int64_t ts_us = last_ts_us_ - first_ts_us_ + static_cast<int64_t>(1e6 / timing_.frame_rate_hz);
  using dsp::limits::kStampLimitNs;
  if (offset_ns_ + frame_ns > kStampLimitNs || ts_offset_us_ + ts_us > kStampLimitNs / 1000 ||
      last_frame_ns_ + (offset_ns_ + frame_ns) > kStampLimitNs) {  // (each sum within +-2^62)
    spdlog::warn("replay --loop: pass {} would take the log's times beyond rsd's window (+-2^61 ns): the play ends", passes_ + 1);
    return false;
  }
  offset_ns_ += frame_ns;
  ts_offset_us_ += ts_us;
  return true;
}

bool ReplaySource::take_frame(const dsp::ImageView& dst, FrameMeta& meta) {
  const formats::DecodeStatus st = formats::decode_frame(ev_.data.data(), ev_.data.size(), img_, frame_, why_);
  if (st != formats::DecodeStatus::Ok) {
    reader_->skip(formats::to_skip(st), ev_.offset, "channel '" + ev_.channel + "': " + why_);
    return false;
  }
  if (frame_.format.width != first_.format.width || frame_.format.height != first_.format.height ||
      frame_.format.format != first_.format.format) {
    reader_->skip(formats::LogSkip::Undecodable, ev_.offset,
                  "frame of " + std::to_string(frame_.format.width) + "x" + std::to_string(frame_.format.height) +
                      " in a log that started with " + std::to_string(first_.format.width) + "x" +
                      std::to_string(first_.format.height));
    return false;
  }
  formats::copy_pixels(img_, dst);
  meta = frame_.meta;
  if (frames_this_pass_ == 0 && passes_ == 0) first_frame_ns_ = meta.first_row_ns;
  last_frame_ns_ = std::max(last_frame_ns_, meta.first_row_ns);
  meta.first_row_ns += offset_ns_;
  frames_.fetch_add(1, std::memory_order_relaxed);
  ++frames_this_pass_;
  return true;
}

int64_t ReplaySource::on_this_pass(int64_t utime) const {
  const std::optional<dsp::Stamp> t = dsp::Stamp::from_us(utime);
  if (!t) return utime;  // out of the window already: the velocity input refuses and counts it
  const std::optional<dsp::Stamp> moved = t->plus_ns(offset_ns_);
  return moved ? moved->us() : INT64_MAX;  // (the same)
}

void ReplaySource::take_pose() {
  bot_core::pose_t m;
  const formats::DecodeStatus st = formats::decode_checked(ev_.data.data(), ev_.data.size(), m, why_);
  if (st != formats::DecodeStatus::Ok) {
    reader_->skip(formats::to_skip(st), ev_.offset, "channel '" + ev_.channel + "': " + why_);
    return;
  }
  m.utime = on_this_pass(m.utime);
  deliver_pose(m);
}

void ReplaySource::take_velocity() {
  rsd::velocity_t m;
  const formats::DecodeStatus st = formats::decode_checked(ev_.data.data(), ev_.data.size(), m, why_);
  if (st != formats::DecodeStatus::Ok) {
    reader_->skip(formats::to_skip(st), ev_.offset, "channel '" + ev_.channel + "': " + why_);
    return;
  }
  m.utime = on_this_pass(m.utime);
  deliver_velocity(m);
}

}  // namespace rsd::drivers
