// A V4L2 camera (UVC webcams, most CSI sensors with a simple driver) as a CameraSource:
// mmap streaming I/O, poll + DQBUF, each frame copied into the caller's slot and the buffer
// queued back at once. The driver's timestamp becomes the start of exposure of the first row
// read (see v4l2_logic.hpp for the arithmetic).
//
// The device is reached only through V4l2Device, so the whole source runs against a fake
// device in tests; open_v4l2_device() is the real one.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/camera_source.hpp"
#include "drivers/driver.hpp"
#include "drivers/v4l2_device.hpp"
#include "drivers/v4l2_logic.hpp"

namespace rsd::drivers {

struct V4l2Config {
  std::string device = "/dev/video0";
  int width = 640, height = 480;
  std::string pixel_format = "GREY";  // GREY, Y16, YUYV or RGB24; the closest offered is used
  double fps = 30;
  unsigned buffers = 4;  // mmap buffers to ask for (the driver may grant another number)
  // Row timing, which V4L2 does not report: 0 line delay means the readout fills the frame
  // period; 0 exposure means "ask the driver" (V4L2_CID_EXPOSURE_ABSOLUTE) at open and start.
  double line_delay_s = 0;
  dsp::Readout readout = dsp::Readout::TopToBottom;
  double exposure_s = 0;
};

// Throws std::invalid_argument naming the first bad field.
void validate(const V4l2Config& cfg);

struct V4l2Stats {
  std::uint64_t frames = 0;             // delivered
  std::uint64_t dropped = 0;            // gaps in the driver's sequence numbers
  std::uint64_t restarts = 0;           // the sequence went backwards
  std::uint64_t error_frames = 0;       // V4L2_BUF_FLAG_ERROR: skipped
  std::uint64_t short_frames = 0;       // fewer bytes than the format needs: skipped
  std::uint64_t estimated_stamps = 0;   // driver clock unknown: stamped from the dequeue time
};

class V4l2Source final : public CameraSource {
 public:
  // `clock` reads CLOCK_MONOTONIC in ns (tests pass their own).
  explicit V4l2Source(V4l2Config cfg, V4l2Opener opener = open_v4l2_device,
                      std::function<std::int64_t()> clock = {});
  ~V4l2Source() override;
  std::string name() const override { return "v4l2:" + cfg_.device; }
  void open() override;
  FrameFormat format() const override { return negotiated_.frame_format(); }
  dsp::RowTiming timing() const override { return timing_; }
  void start() override;
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) override;
  void stop() override;

  // How the negotiated format differs from the request (empty when it does not).
  const std::vector<std::string>& notes() const { return negotiated_.notes; }
  const V4l2Stats& stats() const { return stats_; }
  // Error-flagged and short frames, skipped (any thread).
  uint64_t refused() const override { return refused_.load(std::memory_order_relaxed); }

 private:
  enum class Delivery { Delivered, Skipped };
  Delivery deliver(const v4l2_buffer& buf, const dsp::ImageView& dst, FrameMeta& meta, std::int64_t dequeued_ns);
  void check_slot(const dsp::ImageView& dst) const;
  void refresh_exposure();
  void close() noexcept;

  V4l2Config cfg_;
  std::uint32_t fourcc_ = 0;
  V4l2Opener opener_;
  std::function<std::int64_t()> clock_;
  std::unique_ptr<V4l2Device> dev_;
  std::unique_ptr<v4l2::BufferRing> ring_;
  v4l2::Negotiated negotiated_;
  dsp::RowTiming timing_;
  v4l2::SequenceTracker sequence_;
  V4l2Stats stats_;
  std::atomic<uint64_t> refused_{0};
  bool streaming_ = false;
};

// The driver's entry (drivers/driver_registry.cpp) and its config section (source.v4l2).
Driver v4l2_driver();
void visit_config(formats::ConfigSection& c, V4l2Config& s);

}  // namespace rsd::drivers
