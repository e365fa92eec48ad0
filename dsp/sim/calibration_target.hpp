// What a landmarks scenario films: a checkerboard, an AprilGrid, or a 3-D point set — as
// landmarks (world points, for recordings) and as a scene (for rendered frames).
#pragma once

#include <vector>

#include "dsp/observation/recording.hpp"
#include "dsp/sim/scene.hpp"

namespace rsd::dsp {

enum class TargetKind { Checkerboard, AprilGrid, Points };

struct TargetSpec {
  TargetKind kind = TargetKind::Checkerboard;
  int rows = 7, cols = 9;     // checkerboard: inner corners; aprilgrid: tags
  double spacing_m = 0.1;     // checkerboard square; aprilgrid tag size
  double tag_spacing = 0.3;   // aprilgrid gap / tag size
  int count = 200;            // points
  double extent_m = 1.0;      // points: half width and height of the box
  double depth_min_m = 0.0, depth_max_m = 2.0;  // points: world z range (the camera rests at -distance)
  unsigned seed = 1;
};

struct Target {
  std::vector<dsp::Landmark> landmarks;  // world frame, target plane at z = 0
  dsp::Scene scene;
};

Target make_target(const TargetSpec& spec);

}  // namespace rsd::dsp
