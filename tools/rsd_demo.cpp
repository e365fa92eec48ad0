// rsd-demo: the built-in simulated rolling-shutter camera, run through the geometry core.
//
// Until the daemon lands this is README command 1: it films a fronto-parallel checkerboard
// with a moving simulated rolling-shutter camera, and for every frame prints how far the
// rolling shutter moved the corners from where a global shutter would have put them, and
// how well back-projection (the basis of rectification) puts them back.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <vector>

#include "tools/common/cli_util.hpp"
#include "dsp/geometry/rs_backprojection.hpp"
#include "dsp/geometry/rs_projection.hpp"

using namespace rsd::dsp;

namespace {

struct Options {
  int frames = 10;
  double fps = 30;
  double depth = 1.5;
  double rev_per_s = 0.25;
  std::vector<double> v{0.4, -0.3, 0.0};
};

std::vector<Eigen::Vector3d> checkerboard_corners(double depth) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = -7; i <= 7; ++i)
    for (int j = -5; j <= 5; ++j) pts.emplace_back(0.05 * i, 0.05 * j, depth);
  return pts;
}

struct FrameStats {
  int seen = 0;
  double mean_shift = 0, max_shift = 0, max_rectify_err = 0;
};

// One frame: corners (given in the camera frame at this frame's start) through the
// rolling-shutter camera, then rectified back to the global-shutter image at frame start.
FrameStats film_frame(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                      const std::vector<Eigen::Vector3d>& corners, double depth) {
  FrameStats s;
  const ScrewMotion motion(tw);
  for (const auto& X : corners) {
    const RsProjection p = project_screw(cam, timing, tw, X);
    if (!p.ok() || !cam.contains(p.pixel)) continue;
    const Eigen::Vector2d gs = cam.project(X).value();
    const auto back = rectify_pixel(cam, timing, motion, DepthModel::fronto_parallel(depth), p.pixel, 0.0);
    const double shift = (p.pixel - gs).norm();
    ++s.seen;
    s.mean_shift += shift;
    s.max_shift = std::max(s.max_shift, shift);
    if (back) s.max_rectify_err = std::max(s.max_rectify_err, (*back - gs).norm());
  }
  if (s.seen) s.mean_shift /= s.seen;
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{
      "rsd-demo: a simulated 640x480 rolling-shutter camera filming a checkerboard while it\n"
      "translates and spins about its optical axis. For each frame it prints how many pixels the\n"
      "rolling shutter moved the corners (against a global shutter at frame start) and the\n"
      "residual after rectifying them with the known motion and depth."};
  app.add_option("--frames", o.frames, "frames to simulate")->check(CLI::Range(1, 100000));
  app.add_option("--fps", o.fps, "frame rate in Hz; rows are read over the whole frame period")
      ->check(CLI::PositiveNumber);
  app.add_option("--depth", o.depth, "distance of the checkerboard plane, metres")->check(CLI::PositiveNumber);
  app.add_option("--rev-per-s", o.rev_per_s, "spin about the optical axis, revolutions per second");
  app.add_option("--v", o.v, "camera-frame velocity vx,vy,vz of the scene, m/s")->delimiter(',')->expected(3);
  if (const auto rc = rsd::tools::parse_command_line(app, argc, argv)) return *rc;

  const CameraModel cam = CameraModel::from_hfov(640, 480, 40.0 * M_PI / 180.0);
  const RowTiming timing = RowTiming::full_frame(cam.height, o.fps);
  Twist tw;
  tw.v = {o.v[0], o.v[1], o.v[2]};
  tw.w = {0, 0, 2 * M_PI * o.rev_per_s};
  std::printf("rsd-demo: simulated camera %dx%d, f = %.1f px, %.2f fps, line delay %.3f us (r = %.0f rows/s)\n",
              cam.width, cam.height, cam.fx, o.fps, timing.line_delay_s * 1e6, timing.r());
  std::printf("motion: v = (%.2f, %.2f, %.2f) m/s, spin %.2f rev/s; checkerboard of %zu corners at %.2f m\n",
              o.v[0], o.v[1], o.v[2], o.rev_per_s, checkerboard_corners(o.depth).size(), o.depth);
  std::printf("%6s %8s %6s %14s %13s %18s\n", "frame", "t0 [s]", "seen", "mean shift px", "max shift px",
              "rectified err px");
  const ScrewMotion world_motion(tw);
  const auto board = checkerboard_corners(o.depth);
  for (int k = 0; k < o.frames; ++k) {
    const double t0 = k / o.fps;
    // Corners in this frame's start camera frame; the board plane there stays at o.depth
    // only while vz = 0 and the spin is about the optical axis, which is what we simulate.
    std::vector<Eigen::Vector3d> corners;
    for (const auto& X : board) corners.push_back(world_motion.at(t0) * X);
    const FrameStats s = film_frame(cam, timing, tw, corners, corners.front().z());
    std::printf("%6d %8.4f %6d %14.3f %13.3f %18.2e\n", k, t0, s.seen, s.mean_shift, s.max_shift,
                s.max_rectify_err);
  }
  std::printf("done: rolling-shutter shifts above are what rsd's rectifier removes.\n");
  return 0;
}
