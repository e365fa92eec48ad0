#include "dsp/rectify/bilinear_sampling.hpp"

namespace rsd::dsp::rectify_detail {

namespace {

template <class T, int C>
Samplers scalar_of() {
  return {sample_row_scalar<T, C>, sample_cells_scalar<T, C>};
}

}  // namespace

SampleKind sample_kind(const SamplePlane& p) {
  if (!p.packed()) {
    if (p.sample_bytes == 1 && p.channels == 1 && p.step == 2) return SampleKind::StridedU8x2;
    if (p.sample_bytes == 1 && p.channels == 2 && p.channel_step == 2 && p.step == 4) return SampleKind::StridedUV4;
    return p.sample_bytes == 2 ? SampleKind::StridedU16 : SampleKind::StridedU8;
  }
  if (p.sample_bytes == 2) return SampleKind::U16;
  return p.channels == 3 ? SampleKind::U8x3 : p.channels == 2 ? SampleKind::U8x2 : SampleKind::U8;
}

Samplers scalar_samplers(SampleKind k) {
  switch (k) {
    case SampleKind::U8: return scalar_of<std::uint8_t, 1>();
    case SampleKind::U8x2: return scalar_of<std::uint8_t, 2>();
    case SampleKind::U8x3: return scalar_of<std::uint8_t, 3>();
    case SampleKind::U16: return scalar_of<std::uint16_t, 1>();
    case SampleKind::StridedU8:
    case SampleKind::StridedU8x2:
    case SampleKind::StridedUV4: return {sample_row_strided<std::uint8_t>, sample_cells_strided<std::uint8_t>};
    case SampleKind::StridedU16: return {sample_row_strided<std::uint16_t>, sample_cells_strided<std::uint16_t>};
  }
  return {};
}

Samplers pick_samplers(SampleKind k, bool simd) { return simd ? dispatched_samplers(k) : scalar_samplers(k); }

}  // namespace rsd::dsp::rectify_detail
