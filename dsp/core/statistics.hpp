// Order statistics of samples, one convention everywhere: the q-quantile of n samples is
// the element of rank floor(q n) (0-based) in sorted order, so the median of an even count is
// the upper of the two middle samples. Takes the samples by value: it partially sorts them.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace rsd::dsp {

// NaN-free samples; 0 for none.
inline double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

inline double median(std::vector<double> v) { return quantile(std::move(v), 0.5); }

}  // namespace rsd::dsp
