// Independent ground truth for the rolling-shutter constraint: a dense scan of the capture
// window for the first sign change of pi_y(P(t) X) - (r t - v0), then plain bisection.
// Deliberately naive (no shared code with the solvers under test but the camera model).
#pragma once

#include <cmath>
#include <limits>
#include <optional>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::test {

struct BruteForceSolution {
  double t_c;
  Eigen::Vector2d pixel;
};

inline std::optional<BruteForceSolution> brute_force_project(const dsp::CameraModel& cam,
                                                             const dsp::RowTiming& timing,
                                                             const dsp::CameraMotion& motion,
                                                             const Eigen::Vector3d& X, double t0,
                                                             double t1, int samples = 20000) {
  const double r = 1.0 / timing.line_delay_s * (timing.readout == dsp::Readout::TopToBottom ? 1 : -1);
  const double first = timing.readout == dsp::Readout::TopToBottom ? 0.0 : timing.height - 1.0;
  auto f = [&](double t) {
    const Eigen::Vector3d Xc = motion.at(t) * X;
    if (!(Xc.z() > 0)) return std::numeric_limits<double>::quiet_NaN();
    const double xn = Xc.x() / Xc.z(), yn = Xc.y() / Xc.z();
    const double r2 = xn * xn + yn * yn;
    const auto& d = cam.dist;
    // Each lens's formula as the format spec writes it (not the camera model's code).
    double yd;
    if (d.model == dsp::LensModel::PinholeEqui) {
      const double rn = std::sqrt(r2), th = std::atan(rn), t2 = th * th;
      const double thd = th * (1 + d.k1 * t2 + d.k2 * t2 * t2 + d.k3 * t2 * t2 * t2 + d.k4 * t2 * t2 * t2 * t2);
      yd = rn > 0 ? yn * thd / rn : yn;
    } else {
      yd = yn * (1 + d.k1 * r2 + d.k2 * r2 * r2 + d.k3 * r2 * r2 * r2) + d.p1 * (r2 + 2 * yn * yn) + 2 * d.p2 * xn * yn;
    }
    return cam.fy * yd + cam.cy - (first + r * t);  // row read at t: first row + r t
  };
  double ta = t0, fa = f(ta);
  for (int i = 1; i <= samples; ++i) {
    const double tb = t0 + (t1 - t0) * i / samples;
    const double fb = f(tb);
    if (std::isfinite(fa) && std::isfinite(fb) && (fa == 0 || (fa < 0) != (fb < 0))) {
      double lo = ta, hi = tb, flo = fa;
      for (int k = 0; k < 200 && hi - lo > 0; ++k) {
        const double mid = 0.5 * (lo + hi);
        if (mid == lo || mid == hi) break;
        const double fm = f(mid);
        if ((fm < 0) == (flo < 0)) lo = mid, flo = fm;
        else hi = mid;
      }
      const double t = 0.5 * (lo + hi);
      const Eigen::Vector3d Xc = motion.at(t) * X;
      return BruteForceSolution{t, cam.project(Xc).value()};
    }
    ta = tb, fa = fb;
  }
  return std::nullopt;
}

}  // namespace rsd::test
