#include "dsp/geometry/rs_projection.hpp"

#include <boost/math/tools/roots.hpp>
#include <cmath>
#include <cstdint>
#include <optional>

#include "dsp/geometry/rs_closed_form.hpp"

namespace rsd::dsp {

const char* to_string(RsStatus s) {
  switch (s) {
    case RsStatus::Ok: return "ok";
    case RsStatus::NoSolution: return "no solution of the rolling-shutter constraint in the capture window";
    case RsStatus::BehindCamera: return "point behind the camera at its capture time";
    case RsStatus::UnsupportedMotion: return "motion or lens outside this case's assumptions";
  }
  return "?";
}

CaptureWindow capture_window(const RowTiming& timing, double margin_rows) {
  const double a = timing.row_time(-margin_rows);
  const double b = timing.row_time(timing.height - 1 + margin_rows);
  return {std::min(a, b), std::max(a, b)};
}

CaptureWindow default_capture_window(const RowTiming& timing) {
  return capture_window(timing, 0.5 * timing.height);
}

namespace {

RsProjection fail(RsStatus s) {
  RsProjection p;
  p.status = s;
  return p;
}

// Project the linearised point X + t m at t = t_c, checking window and depth.
RsProjection finish_linear(const CameraModel& cam, const Eigen::Vector3d& X, const Eigen::Vector3d& m,
                           double t_c, const CaptureWindow& win) {
  if (!std::isfinite(t_c) || !win.contains(t_c)) return fail(RsStatus::NoSolution);
  const Eigen::Vector3d Xc = X + t_c * m;
  if (!(Xc.z() > 0)) return fail(RsStatus::BehindCamera);
  RsProjection p;
  p.status = RsStatus::Ok;
  p.t_c = t_c;
  p.pixel = cam.to_pixel(Xc.head<2>() / Xc.z());
  return p;
}

// Earliest root in the window of a2 t^2 + a1 t + a0 = 0, computed without cancellation.
std::optional<double> earliest_quadratic_root(double a2, double a1, double a0,
                                              const CaptureWindow& win) {
  const double scale = std::abs(a1) + std::abs(a2) * (std::abs(win.t_begin) + std::abs(win.t_end));
  std::optional<double> best;
  auto consider = [&](double t) {
    if (std::isfinite(t) && win.contains(t) && (!best || t < *best)) best = t;
  };
  if (std::abs(a2) * (std::abs(win.t_begin) + std::abs(win.t_end)) <= 1e-14 * scale) {
    if (std::abs(a1) > 1e-300) consider(-a0 / a1);  // effectively linear
    return best;
  }
  const double disc = a1 * a1 - 4 * a2 * a0;
  if (disc < 0) return std::nullopt;
  const double q = -0.5 * (a1 + std::copysign(std::sqrt(disc), a1));
  consider(q / a2);
  if (q != 0) consider(a0 / q);
  return best;
}

RsProjection solve_linearised(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                              const Eigen::Vector3d& X, const CaptureWindow& win) {
  if (!cam.dist.is_identity()) return fail(RsStatus::UnsupportedMotion);
  // The constraint in normalised coordinates: with K applied, fy y_n + cy = r t - v0, so
  // y_n = r_n t - v0_n (rs_closed_form.hpp).
  const auto [r_n, v0_n] = normalised_readout(cam, timing);
  // X_c(t) = X + t m with m = [w]x X + v (paper's linearised P(t)). The constraint
  // (y + t m_y) / (z + t m_z) = r_n t - v0_n becomes a quadratic in t.
  const Eigen::Vector3d m = tw.w.cross(X) + tw.v;
  const double a2 = r_n * m.z();
  const double a1 = r_n * X.z() - v0_n * m.z() - m.y();
  const double a0 = -(v0_n * X.z() + X.y());
  const auto t = earliest_quadratic_root(a2, a1, a0, win);
  if (!t) return fail(RsStatus::NoSolution);
  return finish_linear(cam, X, m, *t, win);
}

}  // namespace

RsProjection project_fronto_parallel(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                                     const Eigen::Vector3d& X, const CaptureWindow& win) {
  if (tw.v.z() != 0 || tw.w.x() != 0 || tw.w.y() != 0 || !cam.dist.is_identity())
    return fail(RsStatus::UnsupportedMotion);
  const NormalisedReadout ro = normalised_readout(cam, timing);
  if (!(X.z() > 0)) return fail(RsStatus::BehindCamera);
  // eq. (4), rs_closed_form.hpp: the denominator r z - v_y - w_z x vanishes
  // when the point's image moves down as fast as the readout: no capture.
  const double den = fronto_parallel_denominator(X, ro, tw);
  if (std::abs(den) <= 1e-12 * (std::abs(ro.r_n * X.z()) + std::abs(tw.v.y()) +
                                std::abs(tw.w.z() * X.x())))
    return fail(RsStatus::NoSolution);
  const double t_c = fronto_parallel_capture_time(X, ro, tw);
  if (!std::isfinite(t_c) || !win.contains(t_c)) return fail(RsStatus::NoSolution);
  RsProjection p;
  p.status = RsStatus::Ok;
  p.t_c = t_c;
  p.pixel = pinhole_pixel(cam, fronto_parallel_image(X, t_c, tw));
  return p;
}

RsProjection project_axial(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                           const Eigen::Vector3d& X, const CaptureWindow& win) {
  if (tw.v.x() != 0 || tw.v.y() != 0 || !tw.w.isZero(0)) return fail(RsStatus::UnsupportedMotion);
  return solve_linearised(cam, timing, tw, X, win);
}

RsProjection project_linearised(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                                const Eigen::Vector3d& X, const CaptureWindow& win) {
  return solve_linearised(cam, timing, tw, X, win);
}

RsProjection project_screw(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                           const Eigen::Vector3d& X, const CaptureWindow& win) {
  return project_trajectory(cam, timing, ScrewMotion(tw), X, win);
}

RsProjection project_trajectory(const CameraModel& cam, const RowTiming& timing,
                                const CameraMotion& motion, const Eigen::Vector3d& X,
                                const CaptureWindow& win) {
  // Residual of eq. (3) in rows; NaN where the point is behind the camera.
  auto residual = [&](double t) {
    const Eigen::Vector3d Xc = motion.at(t) * X;
    if (!(Xc.z() > 0)) return std::numeric_limits<double>::quiet_NaN();
    return cam.to_pixel(Xc.head<2>() / Xc.z()).y() - timing.row_at(t);
  };
  // Bracket: the earliest sign change on a uniform scan. The residual moves at the row
  // rate minus the image velocity, so 64 steps over the window resolve every root pair
  // that is more than 1/64 of the window apart.
  constexpr int kSteps = 64;
  const double h = (win.t_end - win.t_begin) / kSteps;
  double ta = win.t_begin, fa = residual(ta);
  bool saw_front = std::isfinite(fa);
  for (int i = 1; i <= kSteps; ++i) {
    const double tb = (i == kSteps) ? win.t_end : win.t_begin + i * h;
    const double fb = residual(tb);
    saw_front = saw_front || std::isfinite(fb);
    if (std::isfinite(fa) && std::isfinite(fb) && (fa == 0 || (fa < 0) != (fb < 0))) {
      double t_c = ta;
      if (fa != 0) {
        std::uintmax_t iters = 100;
        auto tol = boost::math::tools::eps_tolerance<double>(52);
        const auto br = boost::math::tools::toms748_solve(residual, ta, tb, fa, fb, tol, iters);
        t_c = 0.5 * (br.first + br.second);
      }
      const Eigen::Vector3d Xc = motion.at(t_c) * X;
      RsProjection p;
      p.status = RsStatus::Ok;
      p.t_c = t_c;
      p.pixel = cam.to_pixel(Xc.head<2>() / Xc.z());
      return p;
    }
    ta = tb, fa = fb;
  }
  return fail(saw_front ? RsStatus::NoSolution : RsStatus::BehindCamera);
}

RsProjection project_perspective(const CameraModel& cam, const CameraMotion& motion,
                                 const Eigen::Vector3d& X, double t) {
  const auto px = cam.project(motion.at(t) * X);
  if (!px) return fail(RsStatus::BehindCamera);
  RsProjection p;
  p.status = RsStatus::Ok;
  p.t_c = t;
  p.pixel = *px;
  return p;
}

// Overloads with the default capture window.
RsProjection project_fronto_parallel(const CameraModel& c, const RowTiming& rt, const Twist& tw,
                                     const Eigen::Vector3d& X) {
  return project_fronto_parallel(c, rt, tw, X, default_capture_window(rt));
}
RsProjection project_axial(const CameraModel& c, const RowTiming& rt, const Twist& tw,
                           const Eigen::Vector3d& X) {
  return project_axial(c, rt, tw, X, default_capture_window(rt));
}
RsProjection project_linearised(const CameraModel& c, const RowTiming& rt, const Twist& tw,
                                const Eigen::Vector3d& X) {
  return project_linearised(c, rt, tw, X, default_capture_window(rt));
}
RsProjection project_screw(const CameraModel& c, const RowTiming& rt, const Twist& tw,
                           const Eigen::Vector3d& X) {
  return project_screw(c, rt, tw, X, default_capture_window(rt));
}
RsProjection project_trajectory(const CameraModel& c, const RowTiming& rt, const CameraMotion& m,
                                const Eigen::Vector3d& X) {
  return project_trajectory(c, rt, m, X, default_capture_window(rt));
}

}  // namespace rsd::dsp
