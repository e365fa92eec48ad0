#include "dsp/rectify/bilinear_sampling.hpp"

namespace rsd::dsp::rectify_detail {

namespace {

template <class T, int C>
Samplers scalar_samplers() {
  return {sample_row_scalar<T, C>, sample_affine_scalar<T, C>};
}

}  // namespace

Samplers pick_samplers(PixelFormat f, bool simd) {
#ifdef RSD_HAVE_AVX2_KERNELS
  if (simd) return avx2_samplers(f);
#else
  (void)simd;
#endif
  switch (f) {
    case PixelFormat::Mono8: return scalar_samplers<std::uint8_t, 1>();
    case PixelFormat::Mono16: return scalar_samplers<std::uint16_t, 1>();
    case PixelFormat::Rgb8: return scalar_samplers<std::uint8_t, 3>();
  }
  return {};
}

bool cpu_has_avx2() {
#ifdef RSD_HAVE_AVX2_KERNELS
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

}  // namespace rsd::dsp::rectify_detail
