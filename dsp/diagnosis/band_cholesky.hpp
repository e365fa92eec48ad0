// A symmetric positive-definite band matrix factorised once and solved for any number of
// right-hand sides, by LAPACK (dpbtrf, dpbtrs): the translation nuisance's velocity spline
// (velocity_spline.cpp) has a band of 11 either side of the diagonal over a few thousand unknowns,
// solved in every pass and for every column of the fits' Jacobian. Eigen's sparse Cholesky
// analysed the band's pattern anew on every call (a tenth of the hand-held phone's diagnosis
// under parallax); a band factorisation is n x kd^2 and analyses nothing.
// A value type without shared state: any thread, one object per thread.
#pragma once

#include <Eigen/Core>

namespace rsd::dsp {

class BandCholesky {
 public:
  // `upper`: (kd + 1) x n, upper(kd + i - j, j) = A(i, j) for max(0, j - kd) <= i <= j (LAPACK's
  // upper band storage; the entries above the band in its first columns are not read).
  explicit BandCholesky(Eigen::MatrixXd upper);
  // Whether A was positive definite (otherwise solve leaves b as it is).
  bool ok() const { return ok_; }
  int size() const { return static_cast<int>(factor_.cols()); }
  // b <- A^-1 b, b with size() rows and any number of columns.
  void solve(Eigen::MatrixXd& b) const;

 private:
  Eigen::MatrixXd factor_;  // U in upper band storage, A = U^T U
  bool ok_ = false;
};

}  // namespace rsd::dsp
