// The Wald statistic that keeps a value within its own uncertainty of the nominal from being
// named (dsp/diagnosis/uncertainty.hpp): against the chi-square table and against its meaning,
// the largest squared z-score of any linear combination of the parameters.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <numbers>
#include <vector>

#include "dsp/diagnosis/uncertainty.hpp"

namespace rsd::test {
namespace {

using dsp::ParameterCovariance;

// The chi-square's upper quantiles at p = 0.0027 (the two tails beyond 3 sigmas) for 1 to 6
// degrees of freedom, from the published tables (1: 3^2; 2: -2 ln p).
TEST(Uncertainty, WaldAtThreeSigmasIsTheChiSquaresThreeSigmaQuantile) {
  const double table[] = {9.0, 11.829, 14.156, 16.251, 18.205, 20.062};
  for (int k = 1; k <= 6; ++k) {
    const double bar = dsp::wald_at_three_sigmas(k);
    EXPECT_GE(bar, table[k - 1]) << k;  // never a laxer bar than the table's
    EXPECT_LT(bar, 1.015 * table[k - 1]) << k;
  }
}

// sup over directions g of (g . delta)^2 / (g^T C g), by brute force over the half circle: what
// the Wald statistic delta^T C^-1 delta equals (Cauchy-Schwarz in C's metric).
double worst_z2(const Eigen::Matrix2d& c, const Eigen::Vector2d& delta) {
  double best = 0;
  for (int i = 0; i < 100000; ++i) {
    const double a = std::numbers::pi * i / 100000;
    const Eigen::Vector2d g(std::cos(a), std::sin(a));
    best = std::max(best, std::pow(g.dot(delta), 2) / g.dot(c * g));
  }
  return best;
}

TEST(Uncertainty, WaldIsTheLargestSquaredZOfAnyCombinationUnderTheMoreCautiousEstimate) {
  Eigen::Matrix2d classic, sandwich;
  classic << 4, 1.5, 1.5, 9;
  sandwich << 16, -6, -6, 5;
  const ParameterCovariance both{classic, sandwich};
  const Eigen::Vector2d delta(2, 3);
  const double expected = std::min(worst_z2(classic, delta), worst_z2(sandwich, delta));
  EXPECT_NEAR(both.wald({0, 1}, delta), expected, 1e-6 * expected);
  // One parameter of two: its own variance alone, the smaller z^2 of the two estimates.
  EXPECT_NEAR(both.wald({1}, Eigen::VectorXd::Constant(1, 3.0)), std::min(9.0 / 9, 9.0 / 5), 1e-12);
  // Without a sandwich (too few clusters) the classic estimate alone.
  EXPECT_NEAR((ParameterCovariance{classic, {}}).wald({0}, Eigen::VectorXd::Constant(1, 2.0)), 1.0, 1e-12);
  // A singular block measures nothing: nothing can be told from the nominal by it.
  Eigen::Matrix2d singular;
  singular << 1, 1, 1, 1;
  EXPECT_EQ((ParameterCovariance{singular, {}}).wald({0, 1}, delta), 0.0);
}

}  // namespace
}  // namespace rsd::test
