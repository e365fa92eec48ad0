#include "dsp/rectify/rs_rectifier.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

#include "dsp/rectify/bilinear_sampling.hpp"
#include "dsp/rectify/fixed_point.hpp"
#include "dsp/core/input_limits.hpp"

namespace rsd::dsp {

using namespace rectify_detail;

namespace {

bool finite(const Twist& tw) { return tw.v.allFinite() && tw.w.allFinite(); }

bool same_geometry(const CameraModel& a, const CameraModel& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx &&
         a.cy == b.cy && a.dist == b.dist;
}

}  // namespace

double reference_time(const RowTiming& timing, ReferenceRow ref) {
  if (ref == ReferenceRow::First) return timing.row_time(timing.first_row_read());
  return timing.row_time(0.5 * (timing.height - 1));
}

DepthModel ground_plane(double camera_height_m) {
  return DepthModel::plane(Eigen::Vector3d::UnitY(), camera_height_m);
}

// ---- Construction: everything the frames will need is allocated here -------------------

Rectifier::Rectifier(const CameraModel& cam, const RowTiming& timing, PixelFormat format,
                     const RectifierConfig& cfg)
    : Rectifier(cam, timing, cam, format, cfg) {}

Rectifier::Rectifier(const CameraModel& cam, const RowTiming& timing, const CameraModel& out_cam,
                     PixelFormat format, const RectifierConfig& cfg)
    : cam_(cam), out_(out_cam), timing_(timing), format_(format), cfg_(cfg) {
  if (cam.height != timing.height) throw std::invalid_argument("Rectifier: camera and row timing heights differ");
  for (const CameraModel* c : {&cam_, &out_}) {
    if (!limits::side_ok(c->width) || !limits::side_ok(c->height))
      throw std::invalid_argument(std::string("Rectifier: image sides must be ") + limits::kSide.text);
    if (std::string why; !size_fits(format, c->width, c->height, &why)) throw std::invalid_argument("Rectifier: " + why);
  }
  if (!is_power_of_two(cfg.initial_spacing) || !is_power_of_two(cfg.min_spacing) || cfg.min_spacing < 2 ||
      cfg.min_spacing > cfg.initial_spacing)
    throw std::invalid_argument("Rectifier: spacings must be powers of two, 2 <= min_spacing <= initial_spacing");
  if (!(cfg.tolerance_px > 0) || cfg.table_step_rows < 1)
    throw std::invalid_argument("Rectifier: tolerance must be positive and the table step at least one row");
  if (cfg.max_bands < 1 || cfg.max_bands > 256) throw std::invalid_argument("Rectifier: max_bands must be 1..256");
  bands_.resize(cfg.max_bands);
  for (RowScratch& b : bands_) b.xs.assign(out_.width, 0), b.ys.assign(out_.width, 0);
  allocate_levels();
  // Pose table over the capture window of rs_projection.hpp: rows -H/2 .. 1.5 H - 1.
  // Room for a step of one row: fast motions refine the table as well as the grid.
  table_v0_ = -0.5 * timing_.height;
  table_.resize(2 * static_cast<std::size_t>(timing_.height));
  simd_ = cfg_.use_simd;
  static_assert(kKinds == kSampleKinds);
  for (int k = 0; k < kKinds; ++k) {
    const Samplers f = pick_samplers(static_cast<SampleKind>(k), simd_);
    sample_row_[k] = f.row, sample_cells_[k] = f.cells;
  }
}

// Levels from the initial spacing down to the minimum; a level needs three nodes each way for
// the second differences. The unit-z rays of the node pixels do not depend on the motion.
void Rectifier::allocate_levels() {
  std::size_t most = 0;
  int widest = 0;
  for (int s = cfg_.initial_spacing; s >= cfg_.min_spacing; s /= 2) {
    Level L;
    L.spacing = s, L.shift = log2_int(s);
    L.nx = (out_.width - 1 + s - 1) / s + 1, L.ny = (out_.height - 1 + s - 1) / s + 1;
    if (L.nx < 3 || L.ny < 3) continue;
    const std::size_t n = static_cast<std::size_t>(L.nx) * L.ny;
    L.ray_x.resize(n), L.ray_y.resize(n), L.ray_ok.resize(n);
    for (int j = 0; j < L.ny; ++j)
      for (int i = 0; i < L.nx; ++i) {
        const std::size_t k = static_cast<std::size_t>(j) * L.nx + i;
        const auto r = out_.ray(Eigen::Vector2d(i * s, j * s));
        L.ray_ok[k] = r.has_value();
        L.ray_x[k] = r ? r->x() : 0, L.ray_y[k] = r ? r->y() : 0;
      }
    most = std::max(most, n), widest = std::max(widest, L.nx);
    levels_.push_back(std::move(L));
  }
  if (levels_.empty()) throw std::invalid_argument("Rectifier: output too small for min_spacing");
  for (Grid* g : {&coarse_, &fine_}) {
    for (Branch* b : {&g->plane, &g->inf}) {
      b->x.resize(most), b->y.resize(most), b->ok.resize(most);
      b->d2x.resize(2 * most), b->d2y.resize(2 * most);
    }
    g->rho.resize(most);
    g->cell_mode.resize(most);
  }
  cell_error_.resize(most), split_.resize(most), split_row_.resize(most), fine_done_.resize(most);
  v_start_.resize(widest);
  for (RowScratch& b : bands_)
    for (NodeRow* r : {&b.coarse, &b.fine}) {
      for (auto* v : {&r->px, &r->py, &r->ix, &r->iy, &r->rho}) v->resize(widest);
      for (auto* v : {&r->fpx, &r->fpy, &r->fix, &r->fiy}) v->resize(widest);
      r->plane_cells.resize(widest), r->inf_cells.resize(widest);
    }
}

// ---- The exact map at one node ---------------------------------------------------------

// Poses at rows v_k = v_lo + k m, and their increments: between two entries the pose is
// interpolated linearly in the row, an error bounded from the table's second differences.
void Rectifier::build_pose_table(const CameraMotion& motion, int step_rows) {
  const double m = step_rows;
  table_inv_step_ = 1.0 / m;
  table_n_ = static_cast<std::size_t>(std::ceil((2.0 * timing_.height - 1) / m)) + 1;
  for (std::size_t k = 0; k < table_n_; ++k) {
    const Eigen::Affine3d g = motion.at(timing_.row_time(table_v0_ + k * m));
    Pose& P = table_[k];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) P.R[3 * r + c] = g.linear()(r, c);
      P.T[r] = g.translation()(r);
    }
  }
  table_d2R_ = table_d2T_ = 0;
  for (std::size_t k = 0; k + 1 < table_n_; ++k) {
    Pose& P = table_[k];
    const Pose& Q = table_[k + 1];
    for (int e = 0; e < 9; ++e) P.dR[e] = Q.R[e] - P.R[e];
    for (int e = 0; e < 3; ++e) P.dT[e] = Q.T[e] - P.T[e];
  }
  for (std::size_t k = 1; k + 1 < table_n_; ++k) {
    double r2 = 0, t2 = 0;
    for (int e = 0; e < 9; ++e) r2 += std::pow(table_[k].dR[e] - table_[k - 1].dR[e], 2);
    for (int e = 0; e < 3; ++e) t2 += std::pow(table_[k].dT[e] - table_[k - 1].dT[e], 2);
    table_d2R_ = std::max(table_d2R_, std::sqrt(r2)), table_d2T_ = std::max(table_d2T_, std::sqrt(t2));
  }
  std::memset(table_[table_n_ - 1].dR, 0, sizeof table_[0].dR);
  std::memset(table_[table_n_ - 1].dT, 0, sizeof table_[0].dT);
}

// Newton's method on the rolling-shutter constraint eq. (3), in rows:
//     F(v) = pi_y(P(t(v)) X) - v = 0,   t(v) = (v + v0) / r   (eq. (1)),
// for the homogeneous point X = (Y, rho) of the paper's P^3. v is the start on entry and the
// root on exit; px the pixel there. gain bounds how far the pose table's interpolation error
// can move the result (docs/rectification.md). The root is the one Newton reaches from the
// start (the node's neighbour): unique while the image moves slower than the readout.
bool Rectifier::solve_node(const double* Y, double rho, double& v, double* px, double* gain) const {
  const double last = static_cast<double>(table_n_ - 1);
  const bool distorted = !cam_.dist.is_identity();
  for (int it = 0; it < 20; ++it) {
    const double u = (v - table_v0_) * table_inv_step_;
    if (!(u >= 0 && u <= last)) return false;  // outside the capture window
    const int k = std::min(static_cast<int>(u), static_cast<int>(last) - 1);
    const double a = u - k;
    const Pose& P = table_[k];
    double X[3], dX[3];
    for (int r = 0; r < 3; ++r) {
      const double* R = P.R + 3 * r;
      const double* dR = P.dR + 3 * r;
      const double inc = dR[0] * Y[0] + dR[1] * Y[1] + dR[2] * Y[2] + rho * P.dT[r];
      X[r] = R[0] * Y[0] + R[1] * Y[1] + R[2] * Y[2] + rho * P.T[r] + a * inc;
      dX[r] = inc * table_inv_step_;
    }
    if (!(X[2] > 0)) return false;  // behind the camera at that instant
    const double iz = 1.0 / X[2];
    Eigen::Vector2d xn(X[0] * iz, X[1] * iz), dxn((dX[0] - xn.x() * dX[2]) * iz, (dX[1] - xn.y() * dX[2]) * iz);
    const Eigen::Vector2d xu = xn;  // on the undistorted plane, for the gain below
    double lens_gain = 1;  // how much the lens stretches a small move of xn: ||J||_inf
    if (distorted) {
      Eigen::Matrix2d J;
      xn = dsp::distort(cam_.dist, xn, J);
      dxn = J * dxn;
      lens_gain = J.cwiseAbs().rowwise().sum().maxCoeff();
    }
    const double pu = cam_.fx * xn.x() + cam_.cx, pv = cam_.fy * xn.y() + cam_.cy;
    const double du = cam_.fx * dxn.x(), dF = cam_.fy * dxn.y() - 1.0;
    if (!(std::abs(dF) > 1e-3)) return false;  // the image runs with the readout
    const double step = -(pv - v) / dF;
    v += step;
    if (std::abs(step) < 1e-7) {
      px[0] = pu + du * step, px[1] = pv + (dF + 1.0) * step;
      const double ny = std::sqrt(Y[0] * Y[0] + Y[1] * Y[1] + Y[2] * Y[2]);
      // A pose error dX moves the undistorted point by at most iz (1 + |x| + |y|) |dX|_inf, the
      // lens stretches that by ||J||_inf (a fisheye's corners shrink it many times over).
      *gain = (1 + std::abs(xu.x()) + std::abs(xu.y())) * iz * lens_gain * (1 + (1 + std::abs(du)) / std::abs(dF)) *
              (table_d2R_ * ny + table_d2T_ * std::abs(rho));
      return std::abs(px[0]) <= kLimit && std::abs(px[1]) <= kLimit;
    }
  }
  return false;
}

// Every node of the current level for one depth choice: the plane (signed inverse depth, so
// that the map continues smoothly past the horizon) or infinity. Warm start: the solution of
// the node above, one spacing on; nodes of a row do not depend on each other, so the CPU
// overlaps their Newton iterations.
// Node columns [i0, i1): each column solved top to bottom, Newton starting from the row above;
// returns the largest table-error gain.
double Rectifier::solve_columns(Branch& b, bool plane_branch, int i0, int i1) {
  const Level& L = levels_[coarse_.level];
  double gain_max = 0;
  for (int i = i0; i < i1; ++i) v_start_[i] = 0;
  for (int j = 0; j < L.ny; ++j)
    for (int i = i0; i < i1; ++i) {
      const std::size_t n = static_cast<std::size_t>(j) * L.nx + i;
      b.ok[n] = 0, b.x[n] = b.y[n] = 0;
      double& v = v_start_[i];
      v += L.spacing * (j > 0);
      double root = v, px[2], gain = 0;
      if (!solve_at(coarse_, n, plane_branch, root, px, &gain)) continue;
      b.x[n] = px[0], b.y[n] = px[1], b.ok[n] = 1, v = root;
      gain_max = std::max(gain_max, gain);
    }
  return gain_max;
}

// The signed inverse depth of node n's point on the plane (0 without one).
double Rectifier::node_rho(const Level& L, std::size_t n) const {
  if (!plane_) return 0.0;
  const double a[3] = {L.ray_x[n], L.ray_y[n], 1.0};
  double na = 0;
  for (int e = 0; e < 3; ++e)
    na += plane_n_[e] * (Rt_ref_[3 * e] * a[0] + Rt_ref_[3 * e + 1] * a[1] + Rt_ref_[3 * e + 2] * a[2]);
  return na / plane_den_;
}

// Node n of grid g for one depth choice: its ray at t_ref meets the plane (at g.rho[n]) or
// infinity in Y, whose rolling-shutter image solve_node finds from row v.
bool Rectifier::solve_at(const Grid& g, std::size_t n, bool plane_branch, double& v, double* px, double* gain) const {
  const Level& L = levels_[g.level];
  if (!L.ray_ok[n]) return false;
  const double r[3] = {L.ray_x[n], L.ray_y[n], 1.0};
  const double rho = plane_branch ? g.rho[n] : 0.0;
  double Y[3];
  for (int e = 0; e < 3; ++e)
    Y[e] = Rt_ref_[3 * e] * r[0] + Rt_ref_[3 * e + 1] * r[1] + Rt_ref_[3 * e + 2] * r[2] + rho * o_ref_[e];
  return solve_node(Y, rho, v, px, gain);
}

// The columns are independent (each column's Newton starts follow its own rows), so bands of
// them go to the executor's threads as the rows of the remap do; the result is the same.
void Rectifier::solve_branch(Branch& b, bool plane_branch) {
  const int nx = levels_[coarse_.level].nx;
  const int parts = executor_ ? std::clamp(std::min(RectifierConfig::bands_for(executor_->concurrency()), nx), 1,
                                           static_cast<int>(bands_.size()))
                              : 1;
  if (parts == 1) {
    gain_max_ = std::max(gain_max_, solve_columns(b, plane_branch, 0, nx));
  } else {
    struct Job {
      Rectifier* self;
      Branch* b;
      bool plane;
      int parts, nx;
    } job{this, &b, plane_branch, parts, nx};
    executor_->run(parts, [](void* ctx, int k) {
      const Job& j = *static_cast<const Job*>(ctx);
      j.self->bands_[k].gain = j.self->solve_columns(*j.b, j.plane, j.nx * k / j.parts, j.nx * (k + 1) / j.parts);
    }, &job);
    for (int k = 0; k < parts; ++k) gain_max_ = std::max(gain_max_, bands_[k].gain);
  }
  second_differences(b);
}

// |second difference| of the node values along x and y (vector norms), centred at the node or,
// on the grid's edge, at its inward neighbour; NaN where a stencil node has no solution.
void Rectifier::second_differences(Branch& b) const {
  const Level& L = levels_[coarse_.level];
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto d2 = [&](std::size_t a, std::size_t c, std::size_t e, float* out) {
    if (!b.ok[a] || !b.ok[c] || !b.ok[e]) {
      out[0] = out[1] = nan;
      return;
    }
    out[0] = static_cast<float>(b.x[a] - 2 * b.x[c] + b.x[e]);
    out[1] = static_cast<float>(b.y[a] - 2 * b.y[c] + b.y[e]);
  };
  for (int j = 0; j < L.ny; ++j)
    for (int i = 0; i < L.nx; ++i) {
      const std::size_t n = static_cast<std::size_t>(j) * L.nx + i;
      const int ic = std::clamp(i, 1, L.nx - 2), jc = std::clamp(j, 1, L.ny - 2);
      const std::size_t cx = static_cast<std::size_t>(j) * L.nx + ic, cy = static_cast<std::size_t>(jc) * L.nx + i;
      d2(cx - 1, cx, cx + 1, &b.d2x[2 * n]);
      d2(cy - L.nx, cy, cy + L.nx, &b.d2y[2 * n]);
    }
}

// ---- Entry points ----------------------------------------------------------------------

RectifyReport Rectifier::rectify(const ImageView& src, const ImageView& dst, const Twist& tw,
                                 const DepthModel& depth, double t_ref) {
  if (!finite(tw) || !std::isfinite(t_ref)) return pass_through(src, dst);
  return rectify(src, dst, ScrewMotion(tw), depth, t_ref);
}

RectifyReport Rectifier::rectify(const ImageView& src, const ImageView& dst, const CameraMotion& motion,
                                 const DepthModel& depth, double t_ref) {
  check_views(src, dst);
  const RectifyReport rep = build_map(motion, depth, t_ref);
  if (rep.mostly_outside()) {  // mostly black: not an honest rectification (RectifyReport)
    RectifyReport out = pass_through(src, dst);
    out.points_checked = rep.points_checked, out.points_inside = rep.points_inside, out.map_outside = true;
    return out;
  }
  remap(src, dst);
  return rep;
}

// Unrectified: a row copy, or through the output camera with no motion at all.
RectifyReport Rectifier::pass_through(const ImageView& src, const ImageView& dst) {
  check_views(src, dst);
  if (!same_geometry(cam_, out_)) {
    RectifyReport rep = build_map(ScrewMotion(Twist{}), DepthModel::at_infinity(), 0.0);
    remap(src, dst);
    rep.rectified = false;
    return rep;
  }
  copy_image(src, dst);
  RectifyReport rep;
  rep.tolerance_px = cfg_.tolerance_px;
  return rep;
}

}  // namespace rsd::dsp
