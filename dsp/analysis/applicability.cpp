#include "dsp/analysis/applicability.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "dsp/geometry/rs_projection.hpp"

namespace rsd::dsp {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

double paper_min_depth(const CameraModel& cam, const RowTiming& timing, double v_y, double max_px) {
  const double r = timing.r();
  if (!(max_px > 0) || !std::isfinite(r) || r == 0) return kNaN;
  // s_alpha = 1 / fy and r_n = r / fy:  z_min = |v_y| / (max_px s_alpha |r_n|).
  const double s_alpha = 1.0 / cam.fy;
  const double r_n = r / cam.fy;
  return std::abs(v_y) / (max_px * s_alpha * std::abs(r_n));
}

const char* to_string(CorrectionReference r) {
  return r == CorrectionReference::FrameStart ? "frame_start" : "middle_row";
}

bool parse_correction_reference(const char* s, CorrectionReference& out) {
  if (std::strcmp(s, "frame_start") == 0) {
    out = CorrectionReference::FrameStart;
    return true;
  }
  if (std::strcmp(s, "middle_row") == 0) {
    out = CorrectionReference::MiddleRow;
    return true;
  }
  return false;
}

ApplicabilityOptions grid_for(const CameraModel& cam, int cols, ApplicabilityOptions base) {
  base.grid_cols = std::max(2, cols);
  const double aspect = cam.width > 1 ? double(cam.height - 1) / double(cam.width - 1) : 1.0;
  base.grid_rows = std::max(2, static_cast<int>(std::lround((base.grid_cols - 1) * aspect)) + 1);
  return base;
}

ApplicabilityResult correction_bound(const CameraModel& cam, const RowTiming& timing,
                                     const Twist& tw, double depth_z,
                                     const ApplicabilityOptions& opt) {
  ApplicabilityResult res;
  res.threshold_px = opt.threshold_px;
  const int nu = std::max(2, opt.grid_cols), nv = std::max(2, opt.grid_rows);
  res.grid_points = nu * nv;

  const ScrewMotion motion(tw);
  const CaptureWindow win = default_capture_window(timing);
  const double t_ref = opt.reference == CorrectionReference::FrameStart
                           ? 0.0
                           : timing.row_time(0.5 * (timing.height - 1));

  double sum = 0, worst = -1;
  int solved = 0;
  for (int j = 0; j < nv; ++j) {
    for (int i = 0; i < nu; ++i) {
      // Pixel grid from corner to corner: (0, 0) ... (width - 1, height - 1).
      const Eigen::Vector2d p(double(i) * (cam.width - 1) / (nu - 1),
                              double(j) * (cam.height - 1) / (nv - 1));
      const auto ray = cam.ray(p);
      if (!ray || !(depth_z > 0) || !std::isfinite(depth_z)) {
        ++res.no_solution;
        continue;
      }
      const Eigen::Vector3d X = depth_z * *ray;
      const RsProjection q = project_screw(cam, timing, tw, X, win);
      const RsProjection ref = project_perspective(cam, motion, X, t_ref);
      if (!q.ok() || !ref.ok()) {
        ++res.no_solution;
        continue;
      }
      const Eigen::Vector2d d = q.pixel - ref.pixel;
      const double n = d.norm();
      sum += n;
      ++solved;
      if (n > worst) {
        worst = n;
        res.worst_pixel = p;
        res.worst_correction = d;
      }
    }
  }
  if (solved == 0) {
    res.max_correction_px = kInf;
    res.mean_correction_px = kInf;
  } else {
    res.max_correction_px = worst;
    res.mean_correction_px = sum / solved;
  }
  res.pinhole_sufficient = res.no_solution == 0 && res.max_correction_px < opt.threshold_px;
  return res;
}

double min_depth_for(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                     const ApplicabilityOptions& opt) {
  if (!(opt.threshold_px > 0)) return kInf;
  // Rotation alone: X = z K^-1 p scales with z and a pure rotation's image does not depend
  // on z, so the rotation's correction is a depth-independent floor.
  Twist rot = tw;
  rot.v.setZero();
  const ApplicabilityResult floor = correction_bound(cam, timing, rot, 1.0, opt);
  if (!floor.pinhole_sufficient) return kInf;
  if (tw.v.isZero(0)) return 0.0;

  auto sufficient = [&](double z) {
    return correction_bound(cam, timing, tw, z, opt).pinhole_sufficient;
  };

  // First guess from the image speed a translation causes: about f |v| (1 + rho) / z
  // pixels per second (rho: largest normalised radius), accumulated over the readout,
  // against the margin the rotation floor leaves.
  const double rho = std::hypot(std::max(cam.cx, cam.width - 1 - cam.cx) / cam.fx,
                                std::max(cam.cy, cam.height - 1 - cam.cy) / cam.fy);
  const double f = std::max(cam.fx, cam.fy);
  const double margin = opt.threshold_px - floor.max_correction_px;
  constexpr double kZMin = 1e-6, kZMax = 1e15;
  double z_hi = std::clamp(4 * f * tw.v.norm() * (1 + rho) * timing.frame_readout_s() / margin,
                           kZMin, kZMax);

  // Bracket: z_hi sufficient, z_lo = z_hi / 2 not (scanning down from a sufficient depth
  // finds the depth below which the verdict is lost for the first time).
  while (!sufficient(z_hi)) {
    z_hi *= 2;
    if (z_hi > kZMax) return kInf;
  }
  double z_lo = z_hi / 2;
  while (sufficient(z_lo)) {
    z_hi = z_lo;
    z_lo /= 2;
    if (z_lo < kZMin) return 0.0;
  }
  // Bisection on log(depth).
  while (z_hi / z_lo - 1 > 1e-9) {
    const double z_mid = std::sqrt(z_lo * z_hi);
    (sufficient(z_mid) ? z_hi : z_lo) = z_mid;
  }
  return z_hi;
}

}  // namespace rsd::dsp
