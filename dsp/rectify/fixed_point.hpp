// The rectifier's number formats: source positions in 16.16 fixed point, their limits, and
// how a map cell is resampled. Shared by the map (rs_rectifier.cpp), its refinement
// (rs_rectifier_grid.cpp) and the per-row resampling (rs_rectifier_remap.cpp).
#pragma once

#include <cmath>
#include <cstdint>

namespace rsd::dsp::rectify_detail {

// Source positions are 16.16 fixed point in the row buffers; a node further than kLimit px
// from the origin is treated as having no solution, so that every value, and every
// difference of two, stays inside int32.
inline constexpr double kLimit = 8192.0;
inline constexpr std::int32_t kSentinel = -(1 << 30);  // -16384 px: all four taps outside
inline constexpr double kFix = 65536.0;

enum CellMode : std::uint8_t { kZero, kPlane, kInfinite, kKink };

// Round to nearest (half away from zero) by truncation: inline, unlike lrint without -fno-math-errno.
// A NaN (a node without a solution) or a position past kLimit has no 16.16 value, and converting
// it to int would be undefined behaviour: it becomes kSentinel (all four taps outside, as the
// node's cells are), the same on every SIMD target (node_row_lerp.cpp).
inline std::int32_t to_fixed(double v) {
  if (!(std::abs(v) <= kLimit)) return kSentinel;
  return static_cast<std::int32_t>(v * kFix + std::copysign(0.5, v));
}

inline bool is_power_of_two(int s) { return s > 0 && (s & (s - 1)) == 0; }

inline int log2_int(int s) {
  int k = 0;
  while ((1 << k) < s) ++k;
  return k;
}


}  // namespace rsd::dsp::rectify_detail
