// GigE Vision cameras (and Aravis' in-process fake camera) through Aravis 0.8.
//
// Cameras are opened by address, never by discovery: Aravis' discovery, and arv_camera_new()
// with an address that does not answer, broadcast to 255.255.255.255. A GigE Vision camera is
// reached with arv_gv_device_new(interface, device): unicast GVCP to the device from the
// local address the kernel routes to it. "Fake_<serial>" is Aravis' in-process fake camera
// (arv_fake_device_new), no network at all.
//
// Buffers are allocated at open(); capture() pops one (waiting at most the timeout), skips
// and counts incomplete ones, copies the image into the caller's slot and gives the buffer
// back. Stamps: see aravis_timestamps.hpp.
//
// Errors: CameraError when there is no camera or it is lost (no answer at the address,
// control channel heartbeat lost, no frame for `lost_after` and no answer to a register
// read); std::runtime_error when the camera is there but cannot do what the configuration
// asks (pixel format, size, rate): retrying would not help.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "drivers/aravis_timestamps.hpp"
#include "drivers/driver.hpp"
#include "drivers/camera_source.hpp"

namespace rsd::drivers {

struct AravisConfig {
  std::string camera = "127.0.0.1";  // IPv4 address of a GigE Vision camera, or Fake_<serial>
  std::string pixel_format = "Mono8";  // Mono8, Mono16, RGB8 (or RGB8Packed)
  int width = 0, height = 0;           // 0: keep the camera's
  int offset_x = 0, offset_y = 0;
  double frame_rate_hz = 0;            // 0: keep the camera's
  // 0: keep the camera's, auto exposure left alone; stamps then assume the exposure read at
  // open() (ExposureEnd stamps and the receipt model depend on it).
  double exposure_s = 0;
  int buffers = 8;                     // allocated at open()
  // Row timing the camera does not tell: 0 line delay means the readout fills the period.
  double line_delay_s = 0;
  dsp::Readout readout = dsp::Readout::TopToBottom;
  // Stamps (aravis_timestamps.hpp): what the camera's stamp marks, the least delay from
  // readout start to the host's receipt; use_camera_clock = false uses host receipt alone.
  CameraStamp stamp = CameraStamp::ExposureStart;
  double leader_delay_s = 0;
  bool use_camera_clock = true;
  ClockMapperOptions clock;
  // No frame for this long while started: ask the camera whether it is still there.
  std::chrono::milliseconds lost_after{2000};
  // Fake_ cameras only: fills each frame (called on Aravis' stream thread) instead of the
  // fake's own ramp; for tests and demos that inject known images. `camera_stamp_ns` is the
  // fake's own stamp of the frame (its clock, CLOCK_REALTIME in Aravis 0.8), the truth a test
  // holds the published stamps to.
  std::function<void(const dsp::ImageView& frame, uint64_t frame_id, int64_t camera_stamp_ns)> fake_fill;
};

struct AravisStats {
  uint64_t frames = 0;          // delivered by capture()
  uint64_t incomplete = 0;      // buffers Aravis gave back not SUCCESS (missing packets, ...)
  uint64_t mismatched = 0;      // complete, but not the configured size or pixel format
  uint64_t underruns = 0;       // frames the stream dropped for want of a free buffer
  uint64_t clock_resets = 0;    // camera clock restarts seen by the stamp mapping
  uint64_t counter_restarts = 0;
  double clock_drift = 0;       // camera clock rate error (host s per camera s, minus 1)
};

class AravisSource final : public CameraSource {
 public:
  explicit AravisSource(AravisConfig cfg);  // checks the configuration (std::invalid_argument)
  ~AravisSource() override;
  std::string name() const override;
  void open() override;
  FrameFormat format() const override;
  dsp::RowTiming timing() const override;
  void start() override;
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) override;
  void stop() override;
  AravisStats stats() const;  // from the thread that calls capture()
  // Incomplete and mismatched buffers, skipped (any thread).
  uint64_t refused() const override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The driver's entry (drivers/driver_registry.cpp) and its config section (source.aravis).
Driver aravis_driver();
void visit_config(formats::ConfigSection& c, AravisConfig& s);

}  // namespace rsd::drivers
