// The translation nuisance's velocity over depth through time (translation.cpp): a uniform cubic
// B-spline of control points in world axes, fitted to the frame pairs' normal equations. A pair's
// unknowns are w = (u(t), u'(t)), the velocity over depth at its time and that velocity's rate of
// change; both are linear in the control points, so the pairs' equations in w become the control
// points' banded normal equations (a pair's time touches four consecutive control points).
//
// Thread contract: a value without shared state; one object per solve, used by one thread.
#pragma once

#include <Eigen/Core>
#include <array>
#include <vector>

namespace rsd::dsp {

class VelocitySpline {
 public:
  static constexpr int kUnknowns = 6;  // a pair's w = (u(t), u'(t))
  using PairNormal = Eigen::Matrix<double, kUnknowns, kUnknowns>;

  // A spline covering the pairs' times (at least one, any order), its knots knot_s > 0 apart.
  VelocitySpline(const std::vector<double>& pair_times, double knot_s);

  // Forgets the pairs' equations added so far (the spline and the pairs' places on it stay).
  void clear();
  // Pair q's normal matrix in w (q indexes the constructor's times).
  void add(size_t q, const PairNormal& N);
  // Each pair's w minimising the added pairs' squared residuals: rows 6q..6q+5 pair q's, one
  // column per column of the right-hand sides B (laid out alike). A light penalty on the control
  // points' second difference decides only where the data leave a direction free (a stretch
  // without pairs, a component no pair shows); zero where the normal matrix is not positive
  // definite.
  Eigen::MatrixXd velocities(const Eigen::MatrixXd& B) const;

  int controls() const { return intervals_ + 3; }

 private:
  // Where a pair's time falls: its first control point, the four's weights and their
  // derivatives by time.
  struct At {
    int first = 0;
    std::array<double, 4> w{}, dw{};
  };
  At at(double t) const;

  double t0_ = 0, knot_ = 1;
  int intervals_ = 1;
  std::vector<At> at_;                                // per pair
  std::vector<std::array<Eigen::Matrix3d, 4>> blocks_;  // [k][o]: control points k and k + o
  double trace_ = 0;
};

}  // namespace rsd::dsp
