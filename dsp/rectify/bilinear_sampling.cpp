#include "dsp/rectify/bilinear_sampling.hpp"

namespace rsd::dsp::rectify_detail {

namespace {

template <class T, int C>
Samplers scalar_of() {
  return {sample_row_scalar<T, C>, sample_affine_scalar<T, C>};
}

}  // namespace

Samplers scalar_samplers(PixelFormat f) {
  switch (f) {
    case PixelFormat::Mono8: return scalar_of<std::uint8_t, 1>();
    case PixelFormat::Mono16: return scalar_of<std::uint16_t, 1>();
    case PixelFormat::Rgb8: return scalar_of<std::uint8_t, 3>();
  }
  return {};
}

Samplers pick_samplers(PixelFormat f, bool simd) { return simd ? dispatched_samplers(f) : scalar_samplers(f); }

}  // namespace rsd::dsp::rectify_detail
