// lerp_node_row on every Highway target (node_row_lerp.hpp). Compiled with -ffp-contract=off
// (dsp/CMakeLists.txt): a fused multiply-add would round once where the reference rounds twice.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "dsp/rectify/node_row_lerp.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep (before highway.h)
#include "hwy/highway.h"

#include "dsp/rectify/fixed_point.hpp"
#include "dsp/rectify/node_row_lerp.hpp"

HWY_BEFORE_NAMESPACE();
namespace rsd::dsp::rectify_detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

void lerp_node_row_simd(const double* top, const double* bot, double w, int n, double* out, std::int32_t* fixed) {
  const hn::ScalableTag<double> d;
  const hn::Rebind<std::int32_t, decltype(d)> di;
  const auto vw = hn::Set(d, w), scale = hn::Set(d, kFix), half = hn::Set(d, 0.5);
  const auto limit = hn::Set(d, kLimit), sentinel = hn::Set(d, kSentinel / kFix);
  const int lanes = static_cast<int>(hn::Lanes(d));
  int i = 0;
  for (; i + lanes <= n; i += lanes) {
    const auto a = hn::LoadU(d, top + i);
    const auto v = hn::Add(a, hn::Mul(vw, hn::Sub(hn::LoadU(d, bot + i), a)));
    hn::StoreU(v, d, out + i);
    // to_fixed: v 2^16 + copysign(0.5, v), truncated (DemoteTo truncates towards zero); a NaN
    // or a value past kLimit becomes kSentinel first (DemoteTo of it is undefined on some targets).
    if (fixed) {
      const auto f = hn::IfThenElse(hn::Le(hn::Abs(v), limit), v, sentinel);
      hn::StoreU(hn::DemoteTo(di, hn::Add(hn::Mul(f, scale), hn::CopySign(half, f))), di, fixed + i);
    }
  }
  lerp_node_row_scalar(top + i, bot + i, w, n - i, out + i, fixed ? fixed + i : nullptr);
}

// NOLINTNEXTLINE(google-readability-namespace-comments)
}  // namespace HWY_NAMESPACE
}  // namespace rsd::dsp::rectify_detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace rsd::dsp::rectify_detail {

void lerp_node_row_scalar(const double* top, const double* bot, double w, int n, double* out, std::int32_t* fixed) {
  for (int i = 0; i < n; ++i) {
    out[i] = top[i] + w * (bot[i] - top[i]);
    if (fixed) fixed[i] = to_fixed(out[i]);
  }
}

HWY_EXPORT(lerp_node_row_simd);

void lerp_node_row(const double* top, const double* bot, double w, int n, double* out, std::int32_t* fixed) {
  HWY_DYNAMIC_DISPATCH(lerp_node_row_simd)(top, bot, w, n, out, fixed);
}

}  // namespace rsd::dsp::rectify_detail
#endif  // HWY_ONCE
