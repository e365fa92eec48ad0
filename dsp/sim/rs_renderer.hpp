// Renders rolling-shutter frames: every row is imaged at its own read time, exactly.
//
// Each pixel's ray is taken at the time its row is read (eq. (1)) from the camera
// pose at that instant and traced into the scene, so the image is the solution of the
// rolling-shutter constraint by construction, not an approximation of it. Optional motion
// blur averages the row over its exposure, centred on the row's read time so that blur
// adds no bias to positions. Nothing is allocated per frame: the renderer can serve as a
// live camera.
#pragma once

#include <random>
#include <vector>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/core/image.hpp"
#include "dsp/geometry/row_timing.hpp"
#include "dsp/sim/scene.hpp"

namespace rsd::dsp {

struct RenderOptions {
  int supersample = 2;        // n x n samples per pixel (anti-aliasing)
  int exposure_samples = 1;   // > 1: motion blur over the row's exposure_s
  double noise_sigma = 0.0;   // additive Gaussian noise, in grey levels of 0..255
  unsigned noise_seed = 1;
};

class RsRenderer {
 public:
  RsRenderer(const CameraModel& cam, const RowTiming& timing, const RenderOptions& opt);

  // One frame whose first row is read at absolute time t_frame; `motion` maps world
  // coordinates to the camera at absolute time t. `out` must match the camera size and be
  // Mono8 or Rgb8. Not thread-safe (it keeps its noise generator and a row buffer).
  void render(const Scene& scene, const CameraMotion& motion, double t_frame, const ImageView& out);

  const CameraModel& camera() const { return cam_; }
  const RowTiming& timing() const { return timing_; }

 private:
  Eigen::Vector3f shade(const Scene& scene, const Eigen::Vector3d& centre, const Eigen::Matrix3d& R_wc,
                        double u, double v) const;
  void draw_points(const Scene& scene, const CameraMotion& motion, double t_frame);
  void write_row(const ImageView& out, int y);

  CameraModel cam_;
  RowTiming timing_;
  RenderOptions opt_;
  std::vector<Eigen::Vector3f> accum_;  // the frame in linear float, allocated once
  // The scene's plane normals, taken once per frame rather than once per ray (allocated at the
  // first frame: a scene keeps its planes).
  std::vector<Eigen::Vector3d> normals_;
  std::mt19937 rng_;
  std::normal_distribution<float> noise_{0.0f, 1.0f};
};

}  // namespace rsd::dsp
