// The rectify stage: looks up the camera's velocity for the frame, turns it into the
// paper's twist, rectifies the rolling-shutter image to a global-shutter one at the
// reference time, and says what it did. Without a valid velocity the frame passes through
// unrectified, with the reason.
#pragma once

#include <memory>

#include "daemon/velocity_buffer.hpp"
#include "drivers/camera_source.hpp"
#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/rs_backprojection.hpp"
#include "dsp/geometry/row_timing.hpp"
#include "dsp/rectify/rs_rectifier.hpp"

namespace rsd::daemon {

enum class DepthKind { Infinite, Plane, Ground };

// The rectified image's camera: the captured one with the rolling shutter removed and its lens
// kept (what downstream visual-inertial odometry expects), or a pinhole of a chosen field of view
// (the lens undone too: straight lines straight).
enum class RectifyOutput { SameLens, Pinhole };

struct RectifyConfig {
  bool enabled = true;
  RectifyOutput output = RectifyOutput::SameLens;
  double output_hfov_deg = 90;   // Pinhole: its horizontal field of view, centred, square pixels
  dsp::ReferenceRow reference = dsp::ReferenceRow::Middle;
  DepthKind depth = DepthKind::Infinite;
  double depth_m = 5.0;          // Plane: distance of the fronto-parallel plane
  double camera_height_m = 1.5;  // Ground: height of the camera above the ground (y down)
  int grid_px = 64;              // the map starts at this node spacing and refines itself to 0.05 px
  bool gyro_only = false;        // ignore linear velocity even when it is known
  double threshold_px = 1.0;     // the applicability verdict's threshold
  // The longest the rectifier waits for the IMU samples covering a frame's last row (a live
  // IMU's message may arrive a little after the frame); beyond it the newest rate is held.
  double imu_wait_ms = 5.0;
  // Threads that resample each frame together: the rectify thread and workers - 1 helpers,
  // created at start (daemon/worker_pool). 1: the rectify thread alone.
  int workers = 1;
};

// The output camera the configuration asks for, given the captured one.
dsp::CameraModel output_camera(const RectifyConfig& cfg, const dsp::CameraModel& captured);

struct RectifyResult {
  bool rectified = false;
  const char* reason = "";
  double w[3] = {0, 0, 0}, v[3] = {0, 0, 0};  // camera's own rates used, camera axes
  double velocity_age_s = 0;
  // The motion past the newest sample was held: how far the frame's last row (with its
  // exposure) reaches beyond it, and how long the rectifier waited for samples first.
  bool extrapolated = false;
  double extrapolated_s = 0;
  double imu_wait_s = 0;
  double max_correction_px = 0;
  bool pinhole_sufficient = true;
  double reference_time_s = 0;
};

class FrameRectifier {
 public:
  // pool: the threads that share the resampling (nullptr: the calling thread alone); it must
  // outlive this object.
  FrameRectifier(const RectifyConfig& cfg, const dsp::CameraModel& cam, const dsp::RowTiming& timing,
                 const drivers::FrameFormat& fmt, dsp::RowExecutor* pool = nullptr);
  ~FrameRectifier();
  // Never allocates: everything is sized in the constructor. `horizon`: how many of the
  // buffer's samples the frame may use (VelocityBuffer::at), all of them by default.
  RectifyResult process(const dsp::ImageView& src, const dsp::ImageView& dst, const drivers::FrameMeta& meta,
                        const VelocityBuffer& velocity, uint64_t horizon = VelocityBuffer::kAll);
  const dsp::RowTiming& timing() const { return timing_; }
  // Which calibration this rectifier was made with, for frame info: "configured" or "online".
  const char* calibration() const { return calibration_; }
  void set_calibration(const char* label) { calibration_ = label; }

 private:
  dsp::DepthModel depth_model() const;
  // Waits (up to imu_wait_ms) for a sample at or after t_ns; fills the wait and extrapolation.
  void wait_for_samples(int64_t t_ns, const VelocityBuffer& velocity, uint64_t horizon, RectifyResult& r) const;
  // The camera's own rates read from the buffer at kKnots times across the frame's rows
  // (interpolated between samples), for the integrated motion; false if any has no valid sample.
  static constexpr int kKnots = 9;
  bool knots(const drivers::FrameMeta& meta, const VelocityBuffer& velocity, uint64_t horizon, bool translate,
             dsp::IntegratedMotion::Knot* out) const;
  RectifyConfig cfg_;
  dsp::CameraModel cam_;
  dsp::RowTiming timing_;
  std::unique_ptr<dsp::Rectifier> rect_;
  const char* calibration_ = "configured";
};

}  // namespace rsd::daemon
