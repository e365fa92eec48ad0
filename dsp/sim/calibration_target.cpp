#include "dsp/sim/calibration_target.hpp"

#include <memory>
#include <random>

#include "dsp/sim/aprilgrid.hpp"
#include "dsp/sim/random_draws.hpp"

namespace rsd::dsp {

namespace {

// A textured wall half a metre behind the target, so that every pixel sees something.
dsp::Plane wall(unsigned seed) {
  return dsp::fronto_parallel(Eigen::Vector3d(0, 0, 0.5), std::make_shared<dsp::NoiseTexture>(seed, 0.05));
}

// Inner corners of a (cols+1) x (rows+1) board, centred on the origin.
Target checkerboard(const TargetSpec& s) {
  Target t;
  for (int i = 0; i < s.rows; ++i)
    for (int j = 0; j < s.cols; ++j)
      t.landmarks.push_back({i * s.cols + j, Eigen::Vector3d((j - 0.5 * (s.cols - 1)) * s.spacing_m,
                                                             (i - 0.5 * (s.rows - 1)) * s.spacing_m, 0.0)});
  dsp::Plane board = dsp::fronto_parallel_checkerboard(0.0, s.cols + 1, s.rows + 1, s.spacing_m);
  // Plane coordinates start at the board's outer corner; one square of white margin.
  board.s_min = board.t_min = -s.spacing_m;
  board.s_max = (s.cols + 2) * s.spacing_m;
  board.t_max = (s.rows + 2) * s.spacing_m;
  t.scene.planes = {board, wall(s.seed)};
  return t;
}

Target aprilgrid(const TargetSpec& s) {
  const AprilGridTarget g = make_aprilgrid({s.rows, s.cols, s.spacing_m, s.tag_spacing});
  Target t;
  const Eigen::Vector2d centre(0.5 * g.width_m, 0.5 * g.height_m);
  for (size_t i = 0; i < g.corners.size(); ++i) {
    const Eigen::Vector2d p = g.corners[i] - centre;
    t.landmarks.push_back({g.corner_ids[i], Eigen::Vector3d(p.x(), p.y(), 0.0)});
  }
  const Eigen::Vector2d corner = -centre - g.grid_origin_in_bitmap_m;  // bitmap's top-left in world x, y
  auto tex = std::make_shared<dsp::BitmapTexture>(g.bitmap, g.pixels_per_m);
  dsp::Plane plane = dsp::fronto_parallel(Eigen::Vector3d(corner.x(), corner.y(), 0.0), tex);
  plane.s_min = plane.t_min = 0;
  plane.s_max = tex->width_m();
  plane.t_max = tex->height_m();
  t.scene.planes = {plane, wall(s.seed)};
  return t;
}

Target points(const TargetSpec& s) {
  Target t;
  std::mt19937 rng(s.seed);
  std::uniform_real_distribution<double> xy(-s.extent_m, s.extent_m), z(s.depth_min_m, s.depth_max_m);
  for (int i = 0; i < s.count; ++i) {
    const double depth = z(rng);  // first: the order of random_draws.hpp, depth then y then x
    const Eigen::Vector2d across = draw(xy, xy, rng);
    const Eigen::Vector3d X(across.x(), across.y(), depth);
    t.landmarks.push_back({i, X});
    t.scene.points.push_back(X);
  }
  t.scene.background = Eigen::Vector3f::Zero();  // bright dots on black, like LEDs or stars
  return t;
}

}  // namespace

Target make_target(const TargetSpec& spec) {
  switch (spec.kind) {
    case TargetKind::Checkerboard: return checkerboard(spec);
    case TargetKind::AprilGrid: return aprilgrid(spec);
    case TargetKind::Points: return points(spec);
  }
  return {};
}

}  // namespace rsd::dsp
