// The rectification map's error bound and the grid's refinement: where bilinear
// interpolation of the map between nodes may err by more than the tolerance, the cell is
// split, down to the finest level.
#include <algorithm>
#include <cmath>
#include <limits>

#include "dsp/rectify/fixed_point.hpp"
#include "dsp/rectify/rs_rectifier.hpp"

namespace rsd::dsp {

using namespace rectify_detail;

// ---- The error bound and the grid's refinement -----------------------------------------

// Bilinear interpolation on an s x s cell errs by at most s^2/8 (max|f_xx| + max|f_yy|)
// (linear interpolation's Peano-kernel bound, once per direction; holds for vector f). The
// maxima over the cell are estimated from the second differences at its corners, s^2 times
// f'' averaged over +-s: the larger of the two corners' values plus their difference (the
// third-derivative term that the averaging can hide).
double Rectifier::cell_bound(const Branch& b, int i, int j) const {
  const Level& L = levels_[level_];
  auto norm = [](float x, float y) { return std::sqrt(x * x + y * y); };
  auto term = [&](const float* a, const float* c) {
    const double t = std::max(norm(a[0], a[1]), norm(c[0], c[1])) + norm(a[0] - c[0], a[1] - c[1]);
    return std::isnan(t) ? std::numeric_limits<double>::infinity() : t;
  };
  const std::size_t n00 = static_cast<std::size_t>(j) * L.nx + i, n01 = n00 + L.nx;
  const double mx = std::max(term(&b.d2x[2 * n00], &b.d2x[2 * n00 + 2]), term(&b.d2x[2 * n01], &b.d2x[2 * n01 + 2]));
  const double my = std::max(term(&b.d2y[2 * n00], &b.d2y[2 * n01]), term(&b.d2y[2 * n00 + 2], &b.d2y[2 * n01 + 2]));
  return (mx + my) / 8.0;
}

namespace {

// True when all four corners of a cell lie more than 2 px beyond one image edge: every
// interpolated position in between does too, so every tap is outside and the cell is black.
bool beyond_one_edge(const Rectifier::Branch& b, const std::size_t* c, int width, int height) {
  bool left = true, right = true, up = true, down = true;
  for (int k = 0; k < 4; ++k) {
    left = left && b.x[c[k]] < -2, right = right && b.x[c[k]] > width + 1;
    up = up && b.y[c[k]] < -2, down = down && b.y[c[k]] > height + 1;
  }
  return left || right || up || down;
}

bool all_ok(const Rectifier::Branch& b, const std::size_t* c) {
  return b.ok[c[0]] && b.ok[c[1]] && b.ok[c[2]] && b.ok[c[3]];
}

}  // namespace

// Classifies every cell (which depth branch it interpolates, or black) and returns the bound
// over the cells that are sampled: interpolation + pose table + fixed-point rounding.
RectifyReport Rectifier::assess_level() {
  const Level& L = levels_[level_];
  RectifyReport rep;
  rep.spacing = L.spacing, rep.tolerance_px = cfg_.tolerance_px;
  double worst = 0;
  for (int j = 0; j + 1 < L.ny; ++j)
    for (int i = 0; i + 1 < L.nx; ++i) {
      const std::size_t n = static_cast<std::size_t>(j) * L.nx + i;
      const std::size_t c[4] = {n, n + 1, n + L.nx, n + L.nx + 1};
      int positive = 0;
      for (std::size_t k : c) positive += plane_ && rho_[k] > 0;
      const bool use_plane = positive > 0, use_inf = positive < 4;
      std::uint8_t mode = use_plane ? (use_inf ? kKink : kPlane) : kInfinite;
      if ((use_plane && !all_ok(plane_b_, c)) || (use_inf && !all_ok(inf_b_, c))) mode = kZero;
      if (mode == kPlane && beyond_one_edge(plane_b_, c, cam_.width, cam_.height)) mode = kZero;
      if (mode == kInfinite && beyond_one_edge(inf_b_, c, cam_.width, cam_.height)) mode = kZero;
      cell_mode_[static_cast<std::size_t>(j) * (L.nx - 1) + i] = mode;
      if (mode == kZero) continue;
      double e = 0;
      if (use_plane) e = std::max(e, cell_bound(plane_b_, i, j));
      if (use_inf) e = std::max(e, cell_bound(inf_b_, i, j));
      if (std::isinf(e)) ++rep.unbounded_cells;
      worst = std::max(worst, e);
    }
  for (std::size_t n = 0; n < static_cast<std::size_t>(L.nx) * L.ny; ++n)  // the branch the model means
    rep.invalid_nodes += !(plane_ && rho_[n] > 0 ? plane_b_.ok[n] : inf_b_.ok[n]);
  // Table: linear interpolation errs by 1/8 of a second difference (times the node's gain).
  table_error_px_ = std::max(cam_.fx, cam_.fy) / 8.0 * gain_max_;
  rep.error_bound_px = worst + table_error_px_ + fixed_point_error(L.spacing);
  return rep;
}

// Fixed point: rounding to 1/256 px, plus the 16.16 step's rounding accumulated over a cell.
double Rectifier::fixed_point_error(int spacing) {
  return std::sqrt(2.0) * (1.0 / 512 + (spacing + 1) / 131072.0);
}

// The level after `level` worth solving when `level` missed the tolerance with bound `bound`.
// Halving the spacing divides the interpolation part of the bound by 4 to 8 (cell_bound: s^2/8
// times second differences that go as s^2, plus their corner differences that go as s^3), so
// a level is skipped only when even the division by 8 leaves it above the tolerance: a skip
// must not cost resolution (a level that would have held), while a level tried in vain costs a
// quarter of the next one's nodes. An unbounded level (invalid stencil nodes) predicts nothing.
std::size_t Rectifier::next_level(std::size_t level, double bound) const {
  double interpolation = bound - table_error_px_ - fixed_point_error(levels_[level].spacing);
  if (!std::isfinite(interpolation)) return level + 1;
  std::size_t next = level + 1;
  for (; next + 1 < levels_.size(); ++next) {
    interpolation /= 8;
    if (interpolation + table_error_px_ + fixed_point_error(levels_[next].spacing) <= cfg_.tolerance_px) break;
  }
  return next;
}

RectifyReport Rectifier::build_map(const CameraMotion& motion, const DepthModel& depth, double t_ref) {
  // The camera at t_ref: X_c = A X + b, so its rays are A^-1 r from the centre o = -A^-1 b.
  const Eigen::Affine3d g = motion.at(t_ref);
  const Eigen::Matrix3d Ainv = g.linear().inverse();
  const Eigen::Vector3d o = -(Ainv * g.translation());
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Rt_ref_[3 * r + c] = Ainv(r, c);
    o_ref_[r] = o(r);
  }
  // A point of the plane n.X = d on the ray o + lambda a has inverse depth rho = 1/lambda =
  // n.a / (d - n.o): homogeneous X = (a + rho o, rho). rho <= 0 (no hit ahead) -> infinity.
  plane_ = !depth.infinite && std::abs(depth.distance - depth.normal.dot(o)) > 1e-12;
  plane_den_ = plane_ ? depth.distance - depth.normal.dot(o) : 1.0;
  for (int e = 0; e < 3; ++e) plane_n_[e] = depth.normal(e);
  // The grid is refined until the bound holds; the pose table too, where its share is large
  // (only for very fast motion: its error grows with the square of the rotation per step).
  RectifyReport rep;
  int solved = 0;
  for (int step = std::min(cfg_.table_step_rows, timing_.height);; step = std::max(1, step / 2)) {
    build_pose_table(motion, step);
    for (level_ = 0;; level_ = next_level(level_, rep.error_bound_px)) {
      rep = solve_level();
      ++solved;
      if (rep.error_bound_px <= cfg_.tolerance_px || level_ + 1 == levels_.size()) break;
      // The table's own error leaves the grid too little of the tolerance: no finer grid can
      // hold it (next_level would jump to the finest, many times the nodes), so the table is
      // refined first, which costs a tenth of a level.
      if (table_error_px_ > 0.5 * cfg_.tolerance_px && step > 1) break;
    }
    if (table_error_px_ <= 0.25 * cfg_.tolerance_px || step == 1) break;
  }
  rep.levels_solved = solved;
  map_ready_ = true;
  rep.rectified = true;
  measure_displacement(rep);
  return rep;
}

// Over the nodes, and the image's last row and column (between nodes when the spacing does not
// divide the size), where a correction usually peaks: the map there is the bilinear
// interpolation of its four nodes, as the sampler uses it.
void Rectifier::measure_displacement(RectifyReport& rep) const {
  const Level& L = levels_[level_];
  const int s = L.spacing;
  double worst = 0;
  rep.points_checked = rep.points_inside = 0;
  auto at = [&](double px, double py) {
    ++rep.points_checked;
    const int i = std::min(static_cast<int>(px) / s, L.nx - 2), j = std::min(static_cast<int>(py) / s, L.ny - 2);
    const double fx = px / s - i, fy = py / s - j;
    const std::size_t n = static_cast<std::size_t>(j) * L.nx + i;
    const std::size_t c[4] = {n, n + 1, n + L.nx, n + L.nx + 1};
    const Branch& b = plane_ && rho_[c[0]] > 0 ? plane_b_ : inf_b_;  // the branch the model means
    for (std::size_t k : c)
      if (!b.ok[k]) return;
    const double w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    double x = 0, y = 0;
    for (int k = 0; k < 4; ++k) x += w[k] * b.x[c[k]], y += w[k] * b.y[c[k]];
    if (!(x >= -0.5 && y >= -0.5 && x <= cam_.width - 0.5 && y <= cam_.height - 0.5)) return;  // black there
    ++rep.points_inside;
    worst = std::max(worst, std::hypot(x - px, y - py));
  };
  const int last_x = out_.width - 1, last_y = out_.height - 1;
  for (int y = 0;; y = std::min(y + s, last_y)) {
    for (int x = 0;; x = std::min(x + s, last_x)) {
      at(x, y);
      if (x == last_x) break;
    }
    if (y == last_y) break;
  }
  rep.max_displacement_px = worst;
}

RectifyReport Rectifier::solve_level() {
  const Level& L = levels_[level_];
  const std::size_t n_nodes = static_cast<std::size_t>(L.nx) * L.ny;
  need_infinite_ = !plane_;
  for (std::size_t n = 0; n < n_nodes; ++n) {
    const double a[3] = {L.ray_x[n], L.ray_y[n], 1.0};
    double na = 0;
    for (int e = 0; e < 3; ++e)
      na += plane_n_[e] * (Rt_ref_[3 * e] * a[0] + Rt_ref_[3 * e + 1] * a[1] + Rt_ref_[3 * e + 2] * a[2]);
    rho_[n] = plane_ ? na / plane_den_ : 0.0;
    need_infinite_ = need_infinite_ || (L.ray_ok[n] && rho_[n] <= 0);
  }
  gain_max_ = 0;
  if (!need_infinite_) std::fill_n(inf_b_.ok.begin(), n_nodes, std::uint8_t{0});
  if (plane_) solve_branch(plane_b_, true);
  if (need_infinite_) solve_branch(inf_b_, false);
  return assess_level();
}

}  // namespace rsd::dsp
