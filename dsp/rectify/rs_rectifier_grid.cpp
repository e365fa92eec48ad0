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
  const Level& L = levels_[coarse_.level];
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

// Which depth branch a cell with nodes c of grid g interpolates, or black.
std::uint8_t Rectifier::classify_cell(const Grid& g, const std::size_t* c) const {
  int positive = 0;
  for (int k = 0; k < 4; ++k) positive += plane_ && g.rho[c[k]] > 0;
  const bool use_plane = positive > 0, use_inf = positive < 4;
  std::uint8_t mode = use_plane ? (use_inf ? kKink : kPlane) : kInfinite;
  if ((use_plane && !all_ok(g.plane, c)) || (use_inf && !all_ok(g.inf, c))) mode = kZero;
  if (mode == kPlane && beyond_one_edge(g.plane, c, cam_.width, cam_.height)) mode = kZero;
  if (mode == kInfinite && beyond_one_edge(g.inf, c, cam_.width, cam_.height)) mode = kZero;
  return mode;
}

// Classifies every cell (which depth branch it interpolates, or black) and returns the bound
// over the cells that are sampled: interpolation + pose table + fixed-point rounding.
RectifyReport Rectifier::assess_level() {
  const Level& L = levels_[coarse_.level];
  RectifyReport rep;
  rep.spacing = rep.fine_spacing = L.spacing, rep.tolerance_px = cfg_.tolerance_px;
  double worst = 0;
  for (int j = 0; j + 1 < L.ny; ++j)
    for (int i = 0; i + 1 < L.nx; ++i) {
      const std::size_t n = static_cast<std::size_t>(j) * L.nx + i, cell = static_cast<std::size_t>(j) * (L.nx - 1) + i;
      const std::size_t c[4] = {n, n + 1, n + L.nx, n + L.nx + 1};
      const std::uint8_t mode = classify_cell(coarse_, c);
      coarse_.cell_mode[cell] = mode;
      cell_error_[cell] = 0;
      if (mode == kZero) continue;
      double e = 0;
      if (mode != kInfinite) e = std::max(e, cell_bound(coarse_.plane, i, j));
      if (mode != kPlane) e = std::max(e, cell_bound(coarse_.inf, i, j));
      if (std::isinf(e)) ++rep.unbounded_cells;
      cell_error_[cell] = static_cast<float>(e);
      worst = std::max(worst, e);
    }
  for (std::size_t n = 0; n < static_cast<std::size_t>(L.nx) * L.ny; ++n)  // the branch the model means
    rep.invalid_nodes += !(plane_ && coarse_.rho[n] > 0 ? coarse_.plane.ok[n] : coarse_.inf.ok[n]);
  table_error_px_ = table_error();
  rep.error_bound_px = worst + table_error_px_ + fixed_point_error(L.spacing);
  return rep;
}

// The pose table's share of the bound: linear interpolation errs by 1/8 of a second difference,
// times the largest gain of a node solved this frame.
double Rectifier::table_error() const { return std::max(cam_.fx, cam_.fy) / 8.0 * gain_max_; }

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
    for (coarse_.level = 0;; coarse_.level = next_level(coarse_.level, rep.error_bound_px)) {
      rep = solve_level();
      ++solved;
      if (rep.error_bound_px <= cfg_.tolerance_px || coarse_.level + 1 == levels_.size()) break;
      // The table's own error leaves the grid too little of the tolerance: no finer grid can
      // hold it (next_level would jump to the finest, many times the nodes), so the table is
      // refined first, which costs a tenth of a level.
      if (table_error_px_ > 0.5 * cfg_.tolerance_px && step > 1) break;
      // A few cells miss: those alone are split into the next level, when that holds them.
      if (refine_cells(rep)) break;
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
  const Level& L = levels_[coarse_.level];
  const int s = L.spacing;
  double worst = 0;
  rep.points_checked = rep.points_inside = 0;
  auto at = [&](double px, double py) {
    ++rep.points_checked;
    int i = std::min(static_cast<int>(px) / s, L.nx - 2), j = std::min(static_cast<int>(py) / s, L.ny - 2);
    const Grid* g = &coarse_;
    const Level* G = &L;
    if (split(i, j)) {  // the fine cell the pixel lies in
      g = &fine_, G = &levels_[fine_.level];
      i = std::min(static_cast<int>(px) / G->spacing, G->nx - 2), j = std::min(static_cast<int>(py) / G->spacing, G->ny - 2);
    }
    const double fx = px / G->spacing - i, fy = py / G->spacing - j;
    const std::size_t n = static_cast<std::size_t>(j) * G->nx + i;
    const std::size_t c[4] = {n, n + 1, n + G->nx, n + G->nx + 1};
    const Branch& b = plane_ && g->rho[c[0]] > 0 ? g->plane : g->inf;  // the branch the model means
    for (std::size_t k : c)
      if (!b.ok[k]) return;
    const double w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    double x = 0, y = 0;
    for (int k = 0; k < 4; ++k) x += w[k] * b.x[c[k]], y += w[k] * b.y[c[k]];
    if (!(x >= -0.5 && y >= -0.5 && x <= cam_.width - 0.5 && y <= cam_.height - 0.5)) return;  // black there
    ++rep.points_inside;
    worst = std::max(worst, std::sqrt((x - px) * (x - px) + (y - py) * (y - py)));
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

// ---- Local refinement ------------------------------------------------------------------
//
// Where only some cells of a level miss the tolerance (a fisheye's corners, the rows read last
// in a fast turn), splitting those alone into the next level costs a fraction of solving that
// level whole, and the resampler keeps the long cells elsewhere. Node (2i, 2j) of the next level
// is node (i, j) of this one, so a split cell adds five nodes. Every pixel's error is bounded by
// its own cell's bound, so a split cell's edge need not meet its unsplit neighbour's exactly.
bool Rectifier::refine_cells(RectifyReport& rep) {
  const std::size_t fl = coarse_.level + 1;
  // A refinement predicted to miss (next_level's division by 8) is not tried.
  if (fl >= levels_.size() || next_level(coarse_.level, rep.error_bound_px) != fl) return false;
  const Level& C = levels_[coarse_.level];
  const Level& F = levels_[fl];
  const int cw = C.nx - 1, ch = C.ny - 1;
  double budget = cfg_.tolerance_px - table_error_px_ - fixed_point_error(C.spacing);
  int missing = 0;
  for (int j = 0; j < ch; ++j) {
    split_row_[j] = 0;
    for (int i = 0; i < cw; ++i) {
      const std::size_t cell = static_cast<std::size_t>(j) * cw + i;
      split_[cell] = coarse_.cell_mode[cell] != kZero && !(cell_error_[cell] <= budget);
      split_row_[j] |= split_[cell], missing += split_[cell];
    }
  }
  if (missing == 0 || 2 * missing > cw * ch) return false;  // most cells: the whole next level costs less
  fine_.level = fl;
  std::fill_n(fine_done_.begin(), static_cast<std::size_t>(F.nx) * F.ny, std::uint8_t{0});
  for (int j = 0; j < ch; ++j)
    for (int i = 0; split_row_[j] && i < cw; ++i)
      if (split_[static_cast<std::size_t>(j) * cw + i])
        for (int b = 2 * j; b <= std::min(2 * j + 2, F.ny - 1); ++b)
          for (int a = 2 * i; a <= std::min(2 * i + 2, F.nx - 1); ++a)
            if (!solve_fine_node(a, b)) return false;
  table_error_px_ = table_error();  // the new nodes' gains too
  budget = cfg_.tolerance_px - table_error_px_ - fixed_point_error(C.spacing);
  double coarse_worst = 0, fine_worst = 0;
  for (int j = 0; j < ch; ++j)
    for (int i = 0; i < cw; ++i) {
      const std::size_t cell = static_cast<std::size_t>(j) * cw + i;
      if (!split_[cell]) {
        coarse_worst = std::max(coarse_worst, static_cast<double>(cell_error_[cell]));
        continue;
      }
      const double e_plane = plane_ ? patch_bound(fine_.plane, coarse_.plane, i, j) : 0.0;
      const double e_inf = need_infinite_ ? patch_bound(fine_.inf, coarse_.inf, i, j) : 0.0;
      for (int b = 2 * j; b <= std::min(2 * j + 1, F.ny - 2); ++b)
        for (int a = 2 * i; a <= std::min(2 * i + 1, F.nx - 2); ++a) {
          const std::size_t n = static_cast<std::size_t>(b) * F.nx + a;
          const std::size_t c[4] = {n, n + 1, n + F.nx, n + F.nx + 1};
          const std::uint8_t mode = classify_cell(fine_, c);
          fine_.cell_mode[static_cast<std::size_t>(b) * (F.nx - 1) + a] = mode;
          if (mode != kZero) fine_worst = std::max({fine_worst, mode != kInfinite ? e_plane : 0.0, mode != kPlane ? e_inf : 0.0});
        }
    }
  // The new nodes' gains may have raised the table's share: every cell, split or not, must hold.
  if (!(std::max(coarse_worst, fine_worst) <= budget)) return false;
  refined_ = true;
  rep.refined_cells = missing, rep.fine_spacing = F.spacing, rep.unbounded_cells = 0;
  rep.error_bound_px = std::max(coarse_worst, fine_worst) + table_error_px_ + fixed_point_error(C.spacing);
  return true;
}

// Node (a, b) of fine_: a node of coarse_ is copied, a new one solved from its coarse
// neighbour's root. false: the node needs the infinite branch, which this frame did not solve.
bool Rectifier::solve_fine_node(int a, int b) {
  const Level& F = levels_[fine_.level];
  const Level& C = levels_[coarse_.level];
  const std::size_t n = static_cast<std::size_t>(b) * F.nx + a, m = static_cast<std::size_t>(b / 2) * C.nx + a / 2;
  if (fine_done_[n]) return true;
  fine_done_[n] = 1;
  const bool coincident = a % 2 == 0 && b % 2 == 0;
  fine_.rho[n] = coincident ? coarse_.rho[m] : node_rho(F, n);
  if (!need_infinite_ && F.ray_ok[n] && fine_.rho[n] <= 0) return false;
  for (const bool plane_branch : {true, false}) {
    Branch& fb = plane_branch ? fine_.plane : fine_.inf;
    const Branch& cb = plane_branch ? coarse_.plane : coarse_.inf;
    if (coincident || !(plane_branch ? plane_ : need_infinite_)) {
      fb.x[n] = cb.x[m], fb.y[n] = cb.y[m], fb.ok[n] = coincident && cb.ok[m];
      continue;
    }
    fb.ok[n] = 0, fb.x[n] = fb.y[n] = 0;
    // At a root the capture row is the source row: the coarse node's, a fine step lower for
    // an odd row (the warm start solve_columns takes from the node above).
    double v = cb.ok[m] ? cb.y[m] + (b % 2) * F.spacing : static_cast<double>(b) * F.spacing, px[2], gain = 0;
    if (!solve_at(fine_, n, plane_branch, v, px, &gain)) continue;
    fb.x[n] = px[0], fb.y[n] = px[1], fb.ok[n] = 1;
    gain_max_ = std::max(gain_max_, gain);
  }
  return true;
}

// cell_bound for the four fine cells of coarse cell (i, j): the second differences at the
// fine spacing through the split cell's middle column and row, and those at its corners on the
// coarse grid divided by 4 (a second difference goes as the spacing squared); the largest plus
// the largest difference between two of them (the third-derivative term).
double Rectifier::patch_bound(const Branch& fine, const Branch& coarse, int i, int j) const {
  const Level& F = levels_[fine_.level];
  const Level& C = levels_[coarse_.level];
  constexpr double kInf = std::numeric_limits<double>::infinity();
  auto spread = [](const float (*v)[2], int count) {  // squares compared, one root each
    double big = 0, diff = 0;
    for (int p = 0; p < count; ++p) {
      big = std::max(big, static_cast<double>(v[p][0]) * v[p][0] + static_cast<double>(v[p][1]) * v[p][1]);
      for (int q = p + 1; q < count; ++q) {
        const double dx = v[p][0] - v[q][0], dy = v[p][1] - v[q][1];
        diff = std::max(diff, dx * dx + dy * dy);
      }
    }
    return std::sqrt(big) + std::sqrt(diff);
  };
  float dx[7][2], dy[7][2];
  int nxs = 0, nys = 0;
  auto fine_d2 = [&](std::size_t p, std::size_t q, std::size_t r, float* out) {
    if (!fine.ok[p] || !fine.ok[q] || !fine.ok[r]) return false;
    out[0] = static_cast<float>(fine.x[p] - 2 * fine.x[q] + fine.x[r]);
    out[1] = static_cast<float>(fine.y[p] - 2 * fine.y[q] + fine.y[r]);
    return true;
  };
  const int a = 2 * i + 1, b = 2 * j + 1;  // the split cell's middle column and row
  for (int r = 2 * j; a + 1 < F.nx && r <= std::min(2 * j + 2, F.ny - 1); ++r) {
    const std::size_t q = static_cast<std::size_t>(r) * F.nx + a;
    if (!fine_d2(q - 1, q, q + 1, dx[nxs++])) return kInf;
  }
  for (int c = 2 * i; b + 1 < F.ny && c <= std::min(2 * i + 2, F.nx - 1); ++c) {
    const std::size_t q = static_cast<std::size_t>(b) * F.nx + c;
    if (!fine_d2(q - F.nx, q, q + F.nx, dy[nys++])) return kInf;
  }
  for (int cj = j; cj <= j + 1; ++cj)
    for (int ci = i; ci <= i + 1; ++ci) {
      const std::size_t m = static_cast<std::size_t>(cj) * C.nx + ci;
      for (int e = 0; e < 2; ++e) dx[nxs][e] = coarse.d2x[2 * m + e] / 4, dy[nys][e] = coarse.d2y[2 * m + e] / 4;
      if (std::isnan(dx[nxs][0]) || std::isnan(dy[nys][0])) return kInf;  // a stencil node without a solution
      ++nxs, ++nys;
    }
  return (spread(dx, nxs) + spread(dy, nys)) / 8.0;
}

RectifyReport Rectifier::solve_level() {
  const Level& L = levels_[coarse_.level];
  const std::size_t n_nodes = static_cast<std::size_t>(L.nx) * L.ny;
  need_infinite_ = !plane_;
  refined_ = false;
  for (std::size_t n = 0; n < n_nodes; ++n) {
    coarse_.rho[n] = node_rho(L, n);
    need_infinite_ = need_infinite_ || (L.ray_ok[n] && coarse_.rho[n] <= 0);
  }
  gain_max_ = 0;
  if (!need_infinite_) std::fill_n(coarse_.inf.ok.begin(), n_nodes, std::uint8_t{0});
  if (plane_) solve_branch(coarse_.plane, true);
  if (need_infinite_) solve_branch(coarse_.inf, false);
  return assess_level();
}

}  // namespace rsd::dsp
