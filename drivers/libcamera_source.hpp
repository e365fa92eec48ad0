// A libcamera camera (Raspberry Pi and other CSI sensors behind an ISP, UVC through
// libcamera's uvcvideo pipeline) as a CameraSource: one stream, FrameBuffers allocated at
// open, every request queued at start and queued again as soon as its frame is copied into
// the caller's slot. Frames are stamped from controls::SensorTimestamp (see libcamera_logic.hpp
// for what it means and on which clock).
//
// libcamera types stay in the .cpp, so including this header needs no libcamera headers.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "drivers/camera_source.hpp"
#include "drivers/driver.hpp"

namespace rsd::drivers {

struct LibcameraConfig {
  std::string camera_id;  // empty: the first camera libcamera lists
  int width = 640, height = 480;
  dsp::PixelFormat format = dsp::PixelFormat::Mono8;
  std::string role = "auto";  // auto (= viewfinder), viewfinder, raw (8-bit mono sensors)
  double fps = 30;
  unsigned buffers = 4;
  // Row timing, which libcamera does not report: 0 line delay means the readout fills the
  // frame period. exposure_s is used when a frame's metadata has no ExposureTime.
  double line_delay_s = 0;
  dsp::Readout readout = dsp::Readout::TopToBottom;
  double exposure_s = 0;
};

// Throws std::invalid_argument naming the first bad field.
void validate(const LibcameraConfig& cfg);

struct LibcameraStats {
  std::uint64_t frames = 0;            // delivered
  std::uint64_t dropped = 0;           // gaps in the frame sequence numbers
  std::uint64_t failed_frames = 0;     // FrameMetadata::FrameError: skipped
  std::uint64_t short_frames = 0;      // plane shorter than the format needs: skipped
  std::uint64_t fallback_stamps = 0;   // no SensorTimestamp: buffer or completion time used
};

class LibcameraSource final : public CameraSource {
 public:
  explicit LibcameraSource(LibcameraConfig cfg);
  ~LibcameraSource() override;
  std::string name() const override;
  // Throws CameraError "no libcamera camera found (N cameras listed)" when there is none.
  void open() override;
  FrameFormat format() const override { return format_; }
  dsp::RowTiming timing() const override { return timing_; }
  void start() override;
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) override;
  void stop() override;

  const std::vector<std::string>& notes() const { return notes_; }  // differences from the request
  const LibcameraStats& stats() const { return stats_; }

 private:
  class Live;
  LibcameraConfig cfg_;
  std::unique_ptr<Live> live_;
  FrameFormat format_;
  dsp::RowTiming timing_;
  std::vector<std::string> notes_;
  LibcameraStats stats_;
};

// The driver's entry (drivers/driver_registry.cpp) and its config section (source.libcamera).
Driver libcamera_driver();
void visit_config(formats::ConfigSection& c, LibcameraConfig& s);

}  // namespace rsd::drivers
