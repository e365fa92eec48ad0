#include "daemon/recording_source.hpp"

#include "drivers/monotonic_clock.hpp"

namespace rsd::daemon {

drivers::CaptureStatus RecordingSource::capture(const dsp::ImageView& dst, drivers::FrameMeta& meta,
                                                std::chrono::milliseconds timeout) {
  meta.wall_ns = 0;
  const drivers::CaptureStatus st = inner_.capture(dst, meta, timeout);
  if (st == drivers::CaptureStatus::Frame) drivers::stamp_wall_clock(meta);  // recorded with it
  if (st == drivers::CaptureStatus::Frame && encoder_) {
    const size_t n = encoder_->encode(dst, meta);
    // Stamped when the frame was captured, like lcm-logger stamps an arriving message.
    if (n) log_.write(channel_.c_str(), formats::wall_clock_us(), encoder_->data(), n);
  }
  return st;
}

}  // namespace rsd::daemon
