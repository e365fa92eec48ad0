// BandCholesky (dsp/diagnosis/band_cholesky.hpp) against Eigen's dense Cholesky of the same
// matrix: a band of the translation spline's width over a few hundred unknowns, several
// right-hand sides at once; a matrix that is not positive definite is reported, not solved.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <stdexcept>

#include "dsp/diagnosis/band_cholesky.hpp"

namespace rsd::test {
namespace {

using dsp::BandCholesky;

// A random symmetric band matrix (kd either side), diagonally dominant by `margin` (negative:
// not positive definite), dense and in LAPACK's upper band storage.
struct Band {
  Eigen::MatrixXd dense, upper;
};
Band random_band(int n, int kd, double margin, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Band b{Eigen::MatrixXd::Zero(n, n), Eigen::MatrixXd::Zero(kd + 1, n)};
  for (int j = 0; j < n; ++j)
    for (int i = std::max(0, j - kd); i < j; ++i) b.dense(i, j) = b.dense(j, i) = u(rng);
  for (int j = 0; j < n; ++j) b.dense(j, j) = b.dense.row(j).cwiseAbs().sum() + margin;
  for (int j = 0; j < n; ++j)
    for (int i = std::max(0, j - kd); i <= j; ++i) b.upper(kd + i - j, j) = b.dense(i, j);
  return b;
}

TEST(BandCholesky, SolvesAsTheDenseCholeskyForEveryRightHandSide) {
  for (const int n : {1, 12, 369}) {
    const Band b = random_band(n, 11, 0.5, 7u + static_cast<unsigned>(n));
    const Eigen::MatrixXd rhs = Eigen::MatrixXd::Random(n, 5);
    const Eigen::MatrixXd expected = b.dense.llt().solve(rhs);
    const BandCholesky chol(b.upper);
    ASSERT_TRUE(chol.ok()) << n;
    Eigen::MatrixXd x = rhs;
    chol.solve(x);
    EXPECT_LT((x - expected).cwiseAbs().maxCoeff(), 1e-12 * (1 + expected.cwiseAbs().maxCoeff())) << n;
    EXPECT_LT((b.dense * x - rhs).cwiseAbs().maxCoeff(), 1e-10) << n;  // and the residual of the system itself
  }
}

TEST(BandCholesky, ANotPositiveDefiniteMatrixIsReportedAndLeavesTheRightHandSide) {
  Band b = random_band(40, 11, 0.5, 3u);
  b.upper(11, 20) = -1.0;  // a negative pivot
  const BandCholesky chol(b.upper);
  EXPECT_FALSE(chol.ok());
  Eigen::MatrixXd x = Eigen::MatrixXd::Ones(40, 2);
  chol.solve(x);
  EXPECT_EQ(x, Eigen::MatrixXd::Ones(40, 2));
  Eigen::MatrixXd wrong = Eigen::MatrixXd::Ones(39, 1);
  const BandCholesky good(random_band(40, 11, 0.5, 4u).upper);
  EXPECT_THROW(good.solve(wrong), std::invalid_argument);
}

}  // namespace
}  // namespace rsd::test
