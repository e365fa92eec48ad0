#include "dsp/analysis/crossed_slits.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>

namespace rsd::dsp {

double distance(const Line3& l, const Eigen::Vector3d& X) {
  return l.direction.cross(X - l.point).norm();
}

double distance(const Line3& a, const Line3& b) {
  const Eigen::Vector3d n = a.direction.cross(b.direction);  // |n| = sin(angle)
  // Below sin ~ sqrt(eps) the common-perpendicular formula loses more digits (relative
  // error eps / |n|) than the parallel formula (error ~ angle * separation): switch there.
  static const double kParallel = std::sqrt(std::numeric_limits<double>::epsilon());
  const double sn = n.norm();
  if (sn < kParallel) return distance(a, b.point);
  return std::abs((b.point - a.point).dot(n)) / sn;
}

Plucker to_plucker(const Line3& l) {
  Plucker L;
  L << l.direction, l.point.cross(l.direction);
  return L;
}

std::optional<Line3> from_plucker(const Plucker& L) {
  const Eigen::Vector3d d = L.head<3>(), m = L.tail<3>();
  const double dd = d.squaredNorm();
  // |m| / |d| is the line's distance from the origin: beyond 1e12 call it at infinity.
  if (!(dd > 1e-24 * m.squaredNorm())) return std::nullopt;
  return Line3{d.cross(m) / dd, d / std::sqrt(dd)};  // foot of the perpendicular from 0
}

double reciprocal_product(const Plucker& a, const Plucker& b) {
  return a.head<3>().dot(b.tail<3>()) + b.head<3>().dot(a.tail<3>());
}

namespace {

// The real roots (a : b) of the binary quadratic c11 a^2 + 2 c12 a b + c22 b^2 = 0, the
// Klein-quadric condition on the pencil a N1 + b N2. Homogeneous pairs avoid dividing by
// a vanishing leading coefficient; q is formed without cancellation.
std::vector<Eigen::Vector2d> pencil_roots(double c11, double c12, double c22) {
  const double scale = std::max({std::abs(c11), std::abs(c12), std::abs(c22)});
  const double disc = c12 * c12 - c11 * c22;
  const double tol = 1e-12 * scale * scale;  // rounding of disc is ~1e-16 scale^2
  if (disc < -tol) return {};
  if (disc <= tol) {  // tangent: one double root; take the better-conditioned form
    const Eigen::Vector2d r1(-c12, c11), r2(c22, -c12);
    return {r1.norm() >= r2.norm() ? r1 : r2};
  }
  const double q = -(c12 + std::copysign(std::sqrt(disc), c12));
  return {Eigen::Vector2d(q, c11), Eigen::Vector2d(c22, q)};
}

}  // namespace

// A line X meets L_i iff their reciprocal product vanishes: four linear equations on the
// six Plücker coordinates of X. Their null space is a pencil a N1 + b N2 (for four lines
// independent in P^5), and the pencil's lines that are lines at all satisfy the Plücker
// relation d . m = 0: a quadratic in (a : b), so 0, 1 or 2 transversals.
Transversals common_transversals(const std::array<Line3, 4>& lines) {
  Eigen::Matrix<double, 4, 6> A;
  for (int i = 0; i < 4; ++i) {
    const Plucker L = to_plucker(lines[i]).normalized();  // homogeneous: equalise the rows
    A.row(i) << L.tail<3>().transpose(), L.head<3>().transpose();  // [m_i, d_i] . (d, m)
  }
  const Eigen::JacobiSVD<Eigen::Matrix<double, 4, 6>> svd(A, Eigen::ComputeFullV);
  Transversals out;
  const auto& s = svd.singularValues();
  if (!(s(3) > 1e-10 * s(0))) {  // rank < 4: a null space of dimension 3 or more
    out.degenerate = true;
    return out;
  }
  const Plucker N1 = svd.matrixV().col(4), N2 = svd.matrixV().col(5);
  const double c11 = 0.5 * reciprocal_product(N1, N1);
  const double c12 = 0.5 * reciprocal_product(N1, N2);
  const double c22 = 0.5 * reciprocal_product(N2, N2);
  if (std::max({std::abs(c11), std::abs(c12), std::abs(c22)}) < 1e-12) {
    out.degenerate = true;  // N1, N2 unit: the whole pencil lies on the Klein quadric
    return out;
  }
  for (const Eigen::Vector2d& ab : pencil_roots(c11, c12, c22)) {
    if (const auto l = from_plucker(ab(0) * N1 + ab(1) * N2)) out.lines.push_back(*l);
    else ++out.at_infinity;
  }
  return out;
}

std::optional<CrossedSlits> crossed_slits(const CameraModel& cam, const RowTiming& timing,
                                          const Twist& tw) {
  if ((tw.w.array() != 0).any() || tw.v.z() != 0 || !cam.dist.is_identity() || tw.v.y() == 0)
    return std::nullopt;
  // Normalised rolling-shutter constraint v_n = r_n t - v0_n (see rs_projection.cpp).
  const double r_n = timing.r() / cam.fy;
  const double v0_n = (timing.v0() + cam.cy) / cam.fy;
  const double vy = tw.v.y();
  CrossedSlits cs;
  cs.slit1 = Line3::through(Eigen::Vector3d::Zero(), Eigen::Vector3d(tw.v.x(), vy, 0));
  // Minus sign: eq. (1) is r t - v0; the paper's section "Fronto-parallel motion"
  // prints +v0 vy / r (see the header).
  const Eigen::Vector3d on_slit2(0, -v0_n * vy / r_n, vy / r_n);
  cs.slit2 = Line3::through(on_slit2, Eigen::Vector3d::UnitX());
  return cs;
}

}  // namespace rsd::dsp
