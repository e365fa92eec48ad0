// The bilinear sampler's SIMD kernels, part 1: four pixels on 32-bit lanes, the fallback of
// every packed plane (windows, gathers, zeros, the scalar code at the borders), and the vector
// types every part uses. Included by bilinear_sampling_simd.cpp once per Highway target.
#if defined(RSD_DSP_RECTIFY_BILINEAR_FOUR_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef RSD_DSP_RECTIFY_BILINEAR_FOUR_INL_H_
#undef RSD_DSP_RECTIFY_BILINEAR_FOUR_INL_H_
#else
#define RSD_DSP_RECTIFY_BILINEAR_FOUR_INL_H_
#endif

#include <algorithm>
#include <cstring>

#include "hwy/highway.h"
#include "dsp/rectify/bilinear_sampling.hpp"

HWY_BEFORE_NAMESPACE();
namespace rsd::dsp::rectify_detail {
namespace HWY_NAMESPACE {
#if HWY_TARGET != HWY_SCALAR
namespace hn = hwy::HWY_NAMESPACE;

using D32 = hn::Full128<std::int32_t>;   // four positions, taps, words
using DU32 = hn::Full128<std::uint32_t>;
using D16 = hn::Full128<std::int16_t>;   // eight Mono8 pixels
using DU16 = hn::Full128<std::uint16_t>;
using D8 = hn::Full128<std::uint8_t>;    // a 16-byte window, byte lookups
using V32 = hn::Vec<D32>;
using V8 = hn::Vec<D8>;

// Vectors are passed one by one, never in structs or arrays: SVE's vectors have no size known
// at compile time and cannot be members.

// Positions (16.16) -> taps and 8-bit weights, as tap() does.
HWY_INLINE void taps4(V32 X, V32 Y, V32& x0, V32& y0, V32& fx, V32& fy) {
  const D32 d;
  const V32 half = hn::Set(d, 128), low = hn::Set(d, 255);
  const V32 x8 = hn::ShiftRight<8>(hn::Add(X, half)), y8 = hn::ShiftRight<8>(hn::Add(Y, half));
  x0 = hn::ShiftRight<8>(x8), y0 = hn::ShiftRight<8>(y8), fx = hn::And(x8, low), fy = hn::And(y8, low);
}

// (p0 (256 - f) + p1 f + 128) >> 8 as (p0 256 + (p1 - p0) f + 128) >> 8: the same integer, and
// never negative, so the arithmetic shift is the scalar code's logical one.
HWY_INLINE V32 lerp(V32 p0, V32 p1, V32 f) {
  const D32 d;
  return hn::ShiftRight<8>(hn::Add(hn::ShiftLeft<8>(p0), hn::Add(hn::Mul(hn::Sub(p1, p0), f), hn::Set(d, 128))));
}

// The bits of each word at kShift, masked.
template <int kShift>
HWY_INLINE V32 field(V32 g, std::uint32_t mask) {
  const D32 d;
  const DU32 du;
  return hn::BitCast(d, hn::And(hn::ShiftRight<kShift>(hn::BitCast(du, g)), hn::Set(du, mask)));
}

// 0 <= v <= limit in every lane.
HWY_INLINE bool all_within(V32 v, int limit) {
  const D32 d;
  return hn::AllTrue(d, hn::And(hn::Gt(v, hn::Set(d, -1)), hn::Lt(v, hn::Set(d, limit + 1))));
}

// ---- Fetching the taps: the words at the left taps on the two rows, top and bot (and at the
// right taps, top_r and bot_r, for RGB24, whose left word holds only one pixel) ----------------

// Bytes of one pixel's word, relative to its first byte: the lookup pattern (0x80: zero).
template <class T, int C>
constexpr std::uint32_t kWordPattern = sizeof(T) == 2 || C == 2 ? 0x03020100u : (C == 3 ? 0x80020100u : 0x80800100u);

HWY_INLINE V32 gather_row(const std::uint8_t* row0, V32 off) {
  const D32 d;
  return hn::GatherOffset(d, reinterpret_cast<const std::int32_t*>(row0), off);
}

template <class T, int C>
HWY_INLINE void gather_words(const SamplePlane& src, V32 x0, V32 y0, V32& top, V32& bot, V32& top_r, V32& bot_r) {
  const D32 d;
  const V32 off = hn::Add(hn::Mul(y0, hn::Set(d, static_cast<std::int32_t>(src.stride))),
                          hn::Mul(x0, hn::Set(d, C * static_cast<int>(sizeof(T)))));
  top = gather_row(src.data, off), bot = gather_row(src.data + src.stride, off);
  if constexpr (C == 3) top_r = gather_row(src.data + 3, off), bot_r = gather_row(src.data + src.stride + 3, off);
}

// The lookup pattern of the words whose first bytes are `first` (window offsets).
template <class T, int C>
HWY_INLINE V8 word_index(V32 first) {
  const D32 d;
  return hn::BitCast(D8(), hn::Add(hn::Mul(first, hn::Set(d, 0x01010101)),
                                   hn::Set(d, static_cast<std::int32_t>(kWordPattern<T, C>))));
}

HWY_INLINE V32 lookup(V8 window, V8 idx) { return hn::BitCast(D32(), hn::TableLookupBytesOr0(window, idx)); }

// Windows: 16 bytes of the rows ya, ya + 1 (and ya + 2) from the first pixel's left tap; taken
// when the four taps lie within kSpan pixels right of it and within one row below.
template <class T, int C>
HWY_INLINE bool window_words(const SamplePlane& src, V32 x0, V32 y0, V32& top, V32& bot, V32& top_r, V32& bot_r) {
  constexpr int kBpp = C * sizeof(T);
  constexpr int kSpan = C == 3 ? 3 : (16 - 2 * kBpp) / kBpp;  // right tap's last byte inside
  const D32 d;
  const D8 d8;
  const int xa = hn::GetLane(x0);
  const int ya = std::min(hn::GetLane(y0), hn::ExtractLane(y0, 3));
  if (xa < 0 || xa * kBpp + 16 > src.width * kBpp || ya < 0 || ya > src.height - 2) return false;
  const V32 i = hn::Sub(x0, hn::Set(d, xa)), dy = hn::Sub(y0, hn::Set(d, ya));
  if (!all_within(i, kSpan) || !all_within(dy, 1)) return false;
  const auto lower = hn::Eq(dy, hn::Set(d, 1));
  const bool straddle = !hn::AllFalse(d, lower);
  if (straddle && ya > src.height - 3) return false;
  const std::uint8_t* p = src.row(ya) + xa * kBpp;
  const V8 r0 = hn::LoadU(d8, p), r1 = hn::LoadU(d8, p + src.stride);
  const V32 byte0 = hn::Mul(i, hn::Set(d, kBpp));
  const V8 left = word_index<T, C>(byte0);
  top = lookup(r0, left), bot = lookup(r1, left);
  if constexpr (C == 3) {
    const V8 right = word_index<T, C>(hn::Add(byte0, hn::Set(d, 3)));
    top_r = lookup(r0, right), bot_r = lookup(r1, right);
    if (straddle) {
      const V8 r2 = hn::LoadU(d8, p + 2 * src.stride);
      top_r = hn::IfThenElse(lower, bot_r, top_r), bot_r = hn::IfThenElse(lower, lookup(r2, right), bot_r);
    }
  }
  if (straddle) {  // pixels one row lower take rows ya + 1, ya + 2
    const V8 r2 = hn::LoadU(d8, p + 2 * src.stride);
    top = hn::IfThenElse(lower, bot, top), bot = hn::IfThenElse(lower, lookup(r2, left), bot);
  }
  return true;
}

// ---- Blending the words and storing four pixels -----------------------------------------

// One colour of RGB24 words: the byte at kShift of each.
template <int kShift>
HWY_INLINE V32 rgb_channel(V32 top, V32 bot, V32 top_r, V32 bot_r, V32 fx, V32 fy) {
  return lerp(lerp(field<kShift>(top, 0xFF), field<kShift>(top_r, 0xFF), fx),
              lerp(field<kShift>(bot, 0xFF), field<kShift>(bot_r, 0xFF), fx), fy);
}

// room: 4 more bytes after the pixels may be written (the row goes on).
template <class T, int C>
HWY_INLINE void blend_store(V32 top, V32 bot, V32 top_r, V32 bot_r, V32 fx, V32 fy, std::uint8_t* out, bool room) {
  if constexpr (C == 1 && sizeof(T) == 1) {
    const V32 t = lerp(field<0>(top, 0xFF), field<8>(top, 0xFF), fx);
    const V32 b = lerp(field<0>(bot, 0xFF), field<8>(bot, 0xFF), fx);
    const hn::Full32<std::uint8_t> d8;
    hn::StoreU(hn::DemoteTo(d8, lerp(t, b, fy)), d8, out);
  } else if constexpr (C == 1) {
    const V32 t = lerp(field<0>(top, 0xFFFF), field<16>(top, 0xFFFF), fx);
    const V32 b = lerp(field<0>(bot, 0xFFFF), field<16>(bot, 0xFFFF), fx);
    const hn::Full64<std::uint16_t> d16;
    hn::StoreU(hn::DemoteTo(d16, lerp(t, b, fy)), d16, reinterpret_cast<std::uint16_t*>(out));
  } else if constexpr (C == 2) {  // U V U V: the word holds both taps of both channels
    const V32 u = lerp(lerp(field<0>(top, 0xFF), field<16>(top, 0xFF), fx), lerp(field<0>(bot, 0xFF), field<16>(bot, 0xFF), fx), fy);
    const V32 v = lerp(lerp(field<8>(top, 0xFF), field<24>(top, 0xFF), fx), lerp(field<8>(bot, 0xFF), field<24>(bot, 0xFF), fx), fy);
    const hn::Full64<std::uint16_t> d16;
    hn::StoreU(hn::DemoteTo(d16, hn::Or(u, hn::ShiftLeft<8>(v))), d16, reinterpret_cast<std::uint16_t*>(out));
  } else {
    const V32 rgb = hn::Or(hn::Or(rgb_channel<0>(top, bot, top_r, bot_r, fx, fy),
                                  hn::ShiftLeft<8>(rgb_channel<8>(top, bot, top_r, bot_r, fx, fy))),
                           hn::ShiftLeft<16>(rgb_channel<16>(top, bot, top_r, bot_r, fx, fy)));
    // R | G << 8 | B << 16 per lane -> 12 bytes (16 written when the row goes on).
    const D8 d8;
    alignas(16) static constexpr std::uint8_t kPack[16] = {0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, 0, 0, 0, 0};
    const V8 packed = hn::TableLookupBytes(hn::BitCast(d8, rgb), hn::Load(d8, kPack));
    if (room) return hn::StoreU(packed, d8, out);
    alignas(16) std::uint8_t buf[16];
    hn::Store(packed, d8, buf);
    std::memcpy(out, buf, 12);
  }
}

// 1: all four taps in the gather region; -1: all four entirely outside (black); 0: mixed.
HWY_INLINE int classify(V32 x0, V32 y0, int width, int height) {
  const D32 d;
  const V32 m1 = hn::Set(d, -1);
  const auto in = hn::And(hn::And(hn::Gt(x0, m1), hn::Lt(x0, hn::Set(d, width - 3))),
                          hn::And(hn::Gt(y0, m1), hn::Lt(y0, hn::Set(d, height - 1))));
  if (hn::AllTrue(d, in)) return 1;
  const auto out = hn::Or(hn::Or(hn::Lt(x0, m1), hn::Gt(x0, hn::Set(d, width - 1))),
                          hn::Or(hn::Lt(y0, m1), hn::Gt(y0, hn::Set(d, height - 1))));
  return hn::AllTrue(d, out) ? -1 : 0;
}

// Four pixels by windows, gathers, zeros or, near the borders, the scalar code.
template <class T, int C>
HWY_INLINE void four(const SamplePlane& src, V32 X, V32 Y, std::uint8_t* out, bool room) {
  const D32 d;
  V32 x0, y0, fx, fy;
  taps4(X, Y, x0, y0, fx, fy);
  V32 top = hn::Zero(d), bot = top, top_r = top, bot_r = top;
  if (window_words<T, C>(src, x0, y0, top, bot, top_r, bot_r))
    return blend_store<T, C>(top, bot, top_r, bot_r, fx, fy, out, room);
  const int k = classify(x0, y0, src.width, src.height);
  if (k > 0) {
    gather_words<T, C>(src, x0, y0, top, bot, top_r, bot_r);
    return blend_store<T, C>(top, bot, top_r, bot_r, fx, fy, out, room);
  }
  if (k < 0) return static_cast<void>(std::memset(out, src.fill, 4 * C * sizeof(T)));  // fill: 8-bit planes only
  alignas(16) std::int32_t xs[4], ys[4];
  hn::Store(X, d, xs), hn::Store(Y, d, ys);
  sample_row_scalar<T, C>(src, xs, ys, out, 4);
}


// 32 -> 16 bits, saturating, in order (lo's lanes, then hi's).
HWY_INLINE hn::Vec<D16> narrow(V32 lo, V32 hi) {
  const hn::Full64<std::int16_t> dh;
  return hn::Combine(D16(), hn::DemoteTo(dh, hi), hn::DemoteTo(dh, lo));
}
#endif  // HWY_TARGET != HWY_SCALAR
// NOLINTNEXTLINE(google-readability-namespace-comments)
}  // namespace HWY_NAMESPACE
}  // namespace rsd::dsp::rectify_detail
HWY_AFTER_NAMESPACE();
#endif  // RSD_DSP_RECTIFY_BILINEAR_FOUR_INL_H_
