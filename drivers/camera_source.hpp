// One interface for every camera source (sim, aravis, v4l2, libcamera, replay, lcm),
// in the spirit of libcamera's pipeline handlers: the core pipeline knows only this.
//
// A source fills frame slots that the pipeline allocated at start; it never allocates per
// frame. It stamps each frame with the start of exposure of the first row read, on
// CLOCK_MONOTONIC — the driver knows what its hardware timestamp means (V4L2's SOE/EOF flags,
// Aravis' camera vs system stamps, libcamera's sensor timestamp) and converts it once here.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>

#include "dsp/core/frame.hpp"
#include "dsp/core/time_line.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::drivers {

// No camera (device missing, unplugged, not answering): the daemon retries with backoff.
struct CameraError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

using dsp::FrameFormat;
using dsp::FrameMeta;

enum class CaptureStatus { Frame, Timeout, EndOfStream };

// Frames' first-row stamps keep one time line (dsp::TimeLine): each after the previous and at
// most a minute later. A repeated, backward or wild stamp costs that frame alone (refused,
// counted); a camera whose clock restarted, or that paused for longer, is followed again from
// its third frame.
inline dsp::TimeLine frame_time_line() { return dsp::TimeLine(60'000'000'000, 3); }

using dsp::VelocitySample;
using VelocitySink = std::function<void(const VelocitySample&)>;

class CameraSource {
 public:
  virtual ~CameraSource() = default;
  virtual std::string name() const = 0;
  // Finds and configures the camera; throws CameraError with a clear reason if there is
  // none. After open(), format() and timing() are valid.
  virtual void open() = 0;
  virtual FrameFormat format() const = 0;
  // The sensor's row timing as configured or calibrated (line delay, readout, exposure).
  virtual dsp::RowTiming timing() const = 0;
  virtual void start() = 0;
  // Waits up to `timeout` for the next frame and copies it into `dst` (format() sized).
  // Throws CameraError when the camera is lost.
  virtual CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) = 0;
  virtual void stop() = 0;
  // Sources that know the camera's motion report it here (called from capture()).
  virtual void set_velocity_sink(VelocitySink) {}
  // What the source received and refused (a damaged, inconsistent or out-of-order frame or
  // message), each counted and its reason logged; any thread may ask.
  virtual uint64_t refused() const { return 0; }
};

}  // namespace rsd::drivers
