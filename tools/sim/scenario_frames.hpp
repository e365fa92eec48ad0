// A scenario's frames as the real (true-model) camera sees them: its simulated recording, the
// true camera and row timing, the target's scene, and the camera's motion through the true time
// model, lever arm and mount. rsd-sim renders frames, logs and images recordings with it; tests
// render the global-shutter truth with it.
#pragma once

#include <memory>
#include <string>

#include "dsp/sim/rs_renderer.hpp"
#include "formats/scenario_file.hpp"

namespace rsd::tools {

struct FrameOptions {
  int count = 0;  // 0: every frame of the scenario
  bool rgb = false;
  double noise = 0;
  int supersample = 2;
  int blur_samples = 1;
  double exposure_s = 0;
  bool pose = false;  // lcm: also the body trajectory as bot_core.pose_t
};

// World-to-camera motion on the camera clock: the recorded body trajectory through the true
// time model, lever arm and mount (X_c = M^T (body(X_w) - l)).
class TrueCameraMotion final : public dsp::CameraMotion {
 public:
  TrueCameraMotion(const dsp::Recording& r, const dsp::TrueModel& m);
  Eigen::Affine3d at(double t) const override;

 private:
  dsp::TrueModel m_;
  dsp::SampledTrajectory body_;
};

struct FrameRig {
  formats::Scenario sc;
  dsp::SimulatedRecording sim;
  dsp::TrueModel truth;
  dsp::RowTiming timing;
  dsp::Scene scene;
  std::unique_ptr<TrueCameraMotion> motion;
  std::unique_ptr<dsp::RsRenderer> renderer;
  size_t frames;
};

// Throws UsageError for a scenario that is not of the landmarks kind.
FrameRig make_rig(const std::string& scenario, const FrameOptions& o);

// `rsd-sim images`: the scenario as an images recording in `out` (frames/NNNNNN.png, images.csv,
// frames.csv, trajectory.csv, points.csv, recording.yaml with the nominal model and the target).
void write_images_recording(const FrameRig& rig, const FrameOptions& o, const std::string& out);

}  // namespace rsd::tools
