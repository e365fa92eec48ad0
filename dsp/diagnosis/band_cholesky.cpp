#include "dsp/diagnosis/band_cholesky.hpp"

#include <cstddef>
#include <stdexcept>

// LAPACK's Fortran interface (liblapack-dev has no C header for it; LAPACKE is another
// package): every argument by reference, the character's hidden length last.
extern "C" {
void dpbtrf_(const char* uplo, const int* n, const int* kd, double* ab, const int* ldab, int* info, std::size_t uplo_len);
void dpbtrs_(const char* uplo, const int* n, const int* kd, const int* nrhs, const double* ab, const int* ldab, double* b,
             const int* ldb, int* info, std::size_t uplo_len);
}

namespace rsd::dsp {

BandCholesky::BandCholesky(Eigen::MatrixXd upper) : factor_(std::move(upper)) {
  const int n = size(), kd = static_cast<int>(factor_.rows()) - 1, ld = static_cast<int>(factor_.rows());
  if (n == 0 || kd < 0) return;
  int info = 0;
  dpbtrf_("U", &n, &kd, factor_.data(), &ld, &info, 1);
  ok_ = info == 0;
}

void BandCholesky::solve(Eigen::MatrixXd& b) const {
  if (!ok_ || b.cols() == 0) return;
  if (b.rows() != size()) throw std::invalid_argument("BandCholesky::solve: right-hand side of another size");
  const int n = size(), kd = static_cast<int>(factor_.rows()) - 1, ld = static_cast<int>(factor_.rows());
  const int nrhs = static_cast<int>(b.cols()), ldb = static_cast<int>(b.rows());
  int info = 0;
  dpbtrs_("U", &n, &kd, &nrhs, factor_.data(), &ld, b.data(), &ldb, &info, 1);
}

}  // namespace rsd::dsp
