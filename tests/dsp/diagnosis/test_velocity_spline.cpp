// VelocitySpline (dsp/diagnosis/velocity_spline.hpp) against analytic cases: a cubic B-spline
// reproduces a velocity linear in time exactly (the second-difference penalty is zero on it), its
// rate u'(t) agrees with the finite difference of its u(t), and the pairs' order does not matter.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <random>
#include <vector>

#include "dsp/diagnosis/velocity_spline.hpp"

namespace rsd::test {
namespace {

using dsp::VelocitySpline;
constexpr int kSplineW = VelocitySpline::kUnknowns;

// Pair times at 30 fps from t0 over `seconds`.
std::vector<double> spline_pair_times(double t0, double seconds) {
  std::vector<double> t;
  for (double s = 0; s <= seconds; s += 1.0 / 30) t.push_back(t0 + s);
  return t;
}

// Right-hand sides of pairs whose N is the identity: B's rows are w itself.
Eigen::MatrixXd identity_pair_rhs(const std::vector<double>& t, const auto& u, const auto& du) {
  Eigen::MatrixXd B(kSplineW * static_cast<Eigen::Index>(t.size()), 1);
  for (size_t q = 0; q < t.size(); ++q)
    B.middleRows<kSplineW>(kSplineW * static_cast<Eigen::Index>(q)) << u(t[q]), du(t[q]);
  return B;
}

Eigen::MatrixXd fit_spline(VelocitySpline& sp, size_t pairs, const Eigen::MatrixXd& B, size_t skip_from = SIZE_MAX) {
  sp.clear();
  for (size_t q = 0; q < pairs; ++q)
    sp.add(q, q >= skip_from ? VelocitySpline::PairNormal(VelocitySpline::PairNormal::Zero()) : VelocitySpline::PairNormal(VelocitySpline::PairNormal::Identity()));
  return sp.velocities(B);
}

TEST(VelocitySpline, AVelocityLinearInTimeIsReproduced) {
  const Eigen::Vector3d a(0.3, -1.2, 0.05), b(-0.4, 0.25, 2.0);
  auto u = [&](double t) { return Eigen::Vector3d(a + b * t); };
  auto du = [&](double) { return b; };
  const std::vector<double> t = spline_pair_times(12.0, 3.0);
  VelocitySpline sp(t, 0.125);
  EXPECT_EQ(sp.controls(), 24 + 3);
  const Eigen::MatrixXd B = identity_pair_rhs(t, u, du), U = fit_spline(sp, t.size(), B);
  EXPECT_LT((U - B).cwiseAbs().maxCoeff(), 1e-6);
}

// Pairs after the first second carry no equations: their u and u' come from the spline alone,
// and u' must be the derivative of u (the weights' slopes against the weights).
TEST(VelocitySpline, ARateIsTheDerivativeOfTheVelocity) {
  std::vector<double> t = spline_pair_times(0.0, 2.0);
  const size_t observed_pairs = t.size();
  const double h = 1e-5;
  const std::vector<double> probes = {0.2, 0.51, 0.77, 0.93};
  for (double p : probes) t.insert(t.end(), {p - h, p, p + h});
  VelocitySpline sp(t, 0.125);
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0, 1);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(kSplineW * static_cast<Eigen::Index>(t.size()), 1);
  for (Eigen::Index i = 0; i < kSplineW * static_cast<Eigen::Index>(observed_pairs); ++i) B(i, 0) = g(rng);
  const Eigen::MatrixXd U = fit_spline(sp, t.size(), B, observed_pairs);
  for (size_t k = 0; k < probes.size(); ++k) {
    const Eigen::Index at = kSplineW * static_cast<Eigen::Index>(observed_pairs + 3 * k);
    const Eigen::Vector3d before = U.block<3, 1>(at, 0), mid_rate = U.block<3, 1>(at + kSplineW + 3, 0),
                          after = U.block<3, 1>(at + 2 * kSplineW, 0);
    const Eigen::Vector3d difference = (after - before) / (2 * h);
    EXPECT_LT((difference - mid_rate).norm(), 1e-5 * (1 + mid_rate.norm())) << "at t = " << probes[k];
    EXPECT_GT(mid_rate.norm(), 0.1);  // the random data move the spline
  }
}

TEST(VelocitySpline, ThePairsOrderDoesNotMatter) {
  const std::vector<double> t = spline_pair_times(3.0, 1.5);
  std::vector<size_t> order(t.size());
  for (size_t q = 0; q < order.size(); ++q) order[q] = q;
  std::shuffle(order.begin(), order.end(), std::mt19937(11));
  std::vector<double> shuffled(t.size());
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0, 1);
  Eigen::MatrixXd B(kSplineW * static_cast<Eigen::Index>(t.size()), 2), Bs(B.rows(), 2);
  for (Eigen::Index i = 0; i < B.size(); ++i) B(i) = g(rng);
  for (size_t q = 0; q < t.size(); ++q) {
    shuffled[q] = t[order[q]];
    Bs.middleRows<kSplineW>(kSplineW * static_cast<Eigen::Index>(q)) = B.middleRows<kSplineW>(kSplineW * static_cast<Eigen::Index>(order[q]));
  }
  VelocitySpline sp(t, 0.125), sps(shuffled, 0.125);
  const Eigen::MatrixXd U = fit_spline(sp, t.size(), B), Us = fit_spline(sps, t.size(), Bs);
  for (size_t q = 0; q < t.size(); ++q)
    EXPECT_LT((Us.middleRows<kSplineW>(kSplineW * static_cast<Eigen::Index>(q)) -
               U.middleRows<kSplineW>(kSplineW * static_cast<Eigen::Index>(order[q])))
                  .cwiseAbs()
                  .maxCoeff(),
              1e-9);
}

}  // namespace
}  // namespace rsd::test
