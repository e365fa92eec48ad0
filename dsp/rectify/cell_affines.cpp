// cell_affines on every Highway target (cell_affines.hpp).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "dsp/rectify/cell_affines.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep (before highway.h)
#include "hwy/highway.h"

#include <algorithm>
#include <type_traits>

#include "dsp/rectify/cell_affines.hpp"

HWY_BEFORE_NAMESPACE();
namespace rsd::dsp::rectify_detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Cells [i, i + lanes) into o (four int32 per cell). In int32, which the nodes' range keeps
// from overflowing (cell_affines.hpp): the scalar reference's int64 arithmetic gives the same
// integers. (The constants are hoisted out of the caller's loop once this is inlined.)
template <class D>
HWY_INLINE void cells_from(D d, const std::int32_t* X, const std::int32_t* Y, int i, int shift, const PlaneScale& g,
                           std::int32_t* o) {
  const auto half = hn::Set(d, (1 << shift) >> 1);
  auto ax = hn::LoadU(d, X + i), ay = hn::LoadU(d, Y + i);
  const auto sx = hn::ShiftRightSame(hn::Add(hn::Sub(hn::LoadU(d, X + i + 1), ax), half), shift);
  auto sy = hn::ShiftRightSame(hn::Add(hn::Sub(hn::LoadU(d, Y + i + 1), ay), half), shift);
  if (!g.unit()) {  // to the plane's samples: (2 a + ox2 s - (o2 65536 - scale)) >> scale
    const auto ox2 = hn::Set(d, g.ox2);
    ax = hn::ShiftRightSame(hn::Sub(hn::Add(hn::Add(ax, ax), hn::Mul(ox2, sx)), hn::Set(d, g.ox2 * 65536 - g.scale_x)), g.scale_x);
    ay = hn::ShiftRightSame(hn::Sub(hn::Add(hn::Add(ay, ay), hn::Mul(ox2, sy)), hn::Set(d, g.oy2 * 65536 - g.scale_y)), g.scale_y);
    sy = hn::Mul(sy, hn::Set(d, g.sy_factor));
  }
  hn::StoreInterleaved4(ax, ay, sx, sy, d, o + 4 * i);
}

void cell_affines_simd(const std::int32_t* X, const std::int32_t* Y, int n, int shift, const PlaneScale& g,
                       Rectifier::Affine* out) {
  static_assert(sizeof(Rectifier::Affine) == 4 * sizeof(std::int32_t) && std::is_standard_layout_v<Rectifier::Affine>,
                "an Affine is four int32 in a row: the cells are stored interleaved");
  const hn::ScalableTag<std::int32_t> d;
  const int lanes = static_cast<int>(hn::Lanes(d));
  if (n < lanes) {  // a row of fewer cells than lanes: through a copy padded with its last node
    constexpr int kMost = HWY_MAX_BYTES / sizeof(std::int32_t);
    HWY_ALIGN std::int32_t x[kMost + 1], y[kMost + 1];
    HWY_ALIGN Rectifier::Affine cells[kMost];
    for (int i = 0; i <= lanes; ++i) x[i] = X[std::min(i, n)], y[i] = Y[std::min(i, n)];
    cells_from(d, x, y, 0, shift, g, reinterpret_cast<std::int32_t*>(cells));
    std::copy(cells, cells + n, out);
    return;
  }
  // When n is not a multiple of the lanes, the last vector overlaps the one before it: its first
  // cells are computed twice, to the same values. (Not through cell_affine, either way: the
  // cells that are not affine may hold any values, whose differences would overflow its int32.)
  auto* o = reinterpret_cast<std::int32_t*>(out);
  for (int i = 0;; i = std::min(i + lanes, n - lanes)) {
    cells_from(d, X, Y, i, shift, g, o);
    if (i == n - lanes) break;
  }
}

// NOLINTNEXTLINE(google-readability-namespace-comments)
}  // namespace HWY_NAMESPACE
}  // namespace rsd::dsp::rectify_detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace rsd::dsp::rectify_detail {

Rectifier::Affine cell_affine(const std::int32_t* X, const std::int32_t* Y, int i, int shift, const PlaneScale& g) {
  const std::int32_t half = (1 << shift) >> 1;
  Rectifier::Affine a{X[i], Y[i], (X[i + 1] - X[i] + half) >> shift, (Y[i + 1] - Y[i] + half) >> shift};
  if (g.unit()) return a;  // (unit planes have no offset)
  const std::int64_t ox2 = g.ox2, oy2 = g.oy2;
  a.ax = static_cast<std::int32_t>((2 * std::int64_t{a.ax} + ox2 * a.sx - ox2 * 65536 + g.scale_x) >> g.scale_x);
  a.ay = static_cast<std::int32_t>((2 * std::int64_t{a.ay} + ox2 * a.sy - oy2 * 65536 + g.scale_y) >> g.scale_y);
  a.sy *= g.sy_factor;
  return a;
}

void cell_affines_scalar(const std::int32_t* X, const std::int32_t* Y, int n, int shift, const PlaneScale& g,
                         Rectifier::Affine* out) {
  for (int i = 0; i < n; ++i) out[i] = cell_affine(X, Y, i, shift, g);
}

HWY_EXPORT(cell_affines_simd);

void cell_affines(const std::int32_t* X, const std::int32_t* Y, int n, int shift, const PlaneScale& g, Rectifier::Affine* out) {
  HWY_DYNAMIC_DISPATCH(cell_affines_simd)(X, Y, n, shift, g, out);
}

}  // namespace rsd::dsp::rectify_detail
#endif  // HWY_ONCE
