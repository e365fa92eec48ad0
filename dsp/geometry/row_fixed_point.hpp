// The rolling-shutter constraint solved for the row by secant iteration: a point seen by a
// moving camera is imaged at the row whose capture time puts it there (Meingast, Geyer and
// Sastry, eq. (3): the row is a fixed point of the projection at the row's time). For the
// diagnosis's gyro motions, where the image moves a few percent of a row per row read, the
// map contracts and a few evaluations settle the row; the bracketing solver of
// rs_projection.hpp (case e) remains the fallback when they do not.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <optional>

namespace rsd::dsp {

struct RowSolution {
  Eigen::Vector2d px;  // pixel_at(row)
  double row;
  double slope;  // of g(v) = pixel_at(v).y - v, the last secant's (NaN when the start already solved it)
};

// The row v with pixel_at(v).y == v (to 1e-6 px) by secant iteration from `v_start`, at most
// twelve steps. `pixel_at(v)`: the predicted pixel (std::optional<Eigen::Vector2d>) when the
// point is read at row v. Started at the observed row, the map contracts by (image velocity x
// line delay), and three evaluations settle the row to 1e-6 px: the pixel is then within that
// contraction times 1e-6. Started at a nearby point's solution with its `slope`, the first
// Newton step lands within the slope's change times the step, and two evaluations settle it.
// nullopt when pixel_at has no pixel on the way or the row does not settle.
template <class PixelAt>
std::optional<RowSolution> fixed_point_row(PixelAt&& pixel_at, double v_start,
                                           double slope = std::numeric_limits<double>::quiet_NaN()) {
  double v0 = v_start;
  std::optional<Eigen::Vector2d> p0 = pixel_at(v0);
  if (!p0) return std::nullopt;
  double g0 = p0->y() - v0;
  double v1 = std::isfinite(slope) ? v0 - g0 / slope : p0->y();
  for (int it = 0; it < 12; ++it) {
    if (std::abs(g0) < 1e-6) return RowSolution{*p0, v0, slope};
    const std::optional<Eigen::Vector2d> p1 = pixel_at(v1);
    if (!p1) return std::nullopt;
    const double g1 = p1->y() - v1;
    const double secant = (g1 - g0) / (v1 - v0);
    const bool usable = std::isfinite(secant) && std::abs(secant) > 1e-6;
    const double v2 = usable ? v1 - g1 / secant : p1->y();
    if (usable) slope = secant;
    v0 = v1, g0 = g1, p0 = p1, v1 = v2;
  }
  if (std::abs(g0) < 1e-6) return RowSolution{*p0, v0, slope};
  return std::nullopt;
}

}  // namespace rsd::dsp
