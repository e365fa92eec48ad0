// The bilinear sampler's SIMD kernels, part 3: RGB24 and U V pairs (NV12's chroma, YUYV's U V),
// four samples per block on 16-bit lanes, at any positions or along affine segments with
// per-block checks.
// Included by bilinear_sampling_simd.cpp once per Highway target, after bilinear_blocks-inl.h
// (whose wide steps, windows and blends it uses).
#if defined(RSD_DSP_RECTIFY_BILINEAR_FOUR_BLOCKS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef RSD_DSP_RECTIFY_BILINEAR_FOUR_BLOCKS_INL_H_
#undef RSD_DSP_RECTIFY_BILINEAR_FOUR_BLOCKS_INL_H_
#else
#define RSD_DSP_RECTIFY_BILINEAR_FOUR_BLOCKS_INL_H_
#endif

#include <algorithm>
#include <cstdint>

#include "hwy/highway.h"
#include "dsp/rectify/bilinear_sampling.hpp"

HWY_BEFORE_NAMESPACE();
namespace rsd::dsp::rectify_detail {
namespace HWY_NAMESPACE {
#if HWY_TARGET != HWY_SCALAR
namespace hn = hwy::HWY_NAMESPACE;

// ---- RGB24, four pixels per block on 16-bit lanes --------------------------------------------
//
// One 16-byte window (5 px) per row and block from the block's first left tap, taken when its
// four taps lie within 3 px right of it and one row below. A block's 12 output bytes are 12
// 16-bit lanes (A: bytes 0-7, B: bytes 8-11 and four spare lanes): each lane looks up its own
// byte pair (left and right tap of its colour) and is blended like Mono8. Per-pixel values reach
// the lanes of their colours by byte lookups from one word per pixel, 3 i | fx << 8 | fy << 16 |
// row << 24 (i: the pixel's tap column in the window).

// Per output lane of A and B: its pixel's word byte (4 k) twice, and the colour's byte
// offsets (c, c + 3) of the left and right taps.
constexpr Pattern kRgbPixelA = per_block({0, 0, 0, 0, 0, 0, 4, 4, 4, 4, 4, 4, 8, 8, 8, 8});
constexpr Pattern kRgbPixelB = per_block({8, 8, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12});
constexpr Pattern kRgbColourA = per_block({0, 3, 1, 4, 2, 5, 0, 3, 1, 4, 2, 5, 0, 3, 1, 4});
constexpr Pattern kRgbColourB = per_block({2, 5, 0, 3, 1, 4, 2, 5, 0, 3, 0, 3, 0, 3, 0, 3});

// Byte `offset` of each lane's pixel word into the lane's low byte (high byte zero).
template <class DB>
HWY_INLINE hn::Vec<hn::Repartition<std::uint16_t, DB>> spread(DB d8, hn::Vec<DB> words, const Pattern& pixel,
                                                            int offset) {
  const hn::Repartition<std::uint16_t, DB> du16;
  const auto sel = hn::Add(load_pattern(d8, pixel), hn::BitCast(d8, hn::Set(du16, static_cast<std::uint16_t>(offset | 0x8000))));
  return hn::BitCast(du16, hn::TableLookupBytesOr0(words, sel));
}

// The blend of A or B (by its lookup patterns) in every block.
template <class DB>
HWY_INLINE hn::Vec<hn::Repartition<std::uint16_t, DB>> rgb_half(DB d8, hn::Vec<DB> r0, hn::Vec<DB> r1, hn::Vec<DB> r2,
                                                              bool straddle, hn::Vec<DB> words, const Pattern& pixel,
                                                              const Pattern& colour) {
  const hn::Repartition<std::uint16_t, DB> du16;
  using VU = hn::Vec<decltype(du16)>;
  const auto idx = hn::Add(hn::TableLookupBytes(words, load_pattern(d8, pixel)), load_pattern(d8, colour));
  const VU fx = spread(d8, words, pixel, 1), fy = spread(d8, words, pixel, 2);
  VU up = hn::BitCast(du16, hn::TableLookupBytes(r0, idx)), down = hn::BitCast(du16, hn::TableLookupBytes(r1, idx));
  if (straddle) {
    const auto m = hn::Eq(spread(d8, words, pixel, 3), hn::Set(du16, 1));
    up = hn::IfThenElse(m, down, up);
    down = hn::IfThenElse(m, hn::BitCast(du16, hn::TableLookupBytes(r2, idx)), down);
  }
  return lerp16(blend_pairs(up, fx), blend_pairs(down, fx), fy);
}

// Bytes [0, n) of each block's 16-bit lanes, narrowed, to out[b] + at (n: 4 or 8), for the
// blocks whose bit in `skip` is clear.
template <class DU16x>
HWY_INLINE void store_per_block(DU16x, hn::Vec<DU16x> v, std::uint8_t* const* out, int at, int n, unsigned skip = 0) {
  const hn::Rebind<std::uint8_t, DU16x> d8n;
  const auto bytes = hn::DemoteTo(d8n, hn::BitCast(hn::RebindToSigned<DU16x>(), v));
  const hn::Full64<std::uint8_t> d64;
  const hn::Full32<std::uint8_t> d32;
  for (int b = 0; b < blocks_of<DU16x>(); ++b) {
    if (skip >> b & 1) continue;
    const auto half = part<blocks_of<DU16x>(), decltype(d64)>(d8n, bytes, b);
    if (n == 8)
      hn::StoreU(half, d64, out[b] + at);
    else
      hn::StoreU(hn::LowerHalf(d32, half), d32, out[b] + at);
  }
}

// The windows of four pixels per block, pixels of kBytes bytes: each block's 16-byte window
// starts at its first left tap (as tap() rounds it), p[b]; rx, ry are the positions relative to
// it in 1/256 px. false when a window would leave the image or a right tap would lie kRight
// pixels or more right of its start, or below the next row (kSlack: bytes the plane's rows have
// fewer than kBytes a sample). straddle: some taps lie one row lower (p[b] then needs a third
// row, which is checked to exist).
template <int kBytes, int kRight, int kSlack = 0, class D32x>
HWY_INLINE bool block_windows(D32x d, const SamplePlane& src, hn::Vec<D32x> X, hn::Vec<D32x> Y, const std::uint8_t** p,
                              hn::Vec<D32x>& rx, hn::Vec<D32x>& ry, bool& straddle) {
  constexpr int kB = blocks_of<D32x>();
  int bx[kB], by[kB], ya_max = 0;
  for (int b = 0; b < kB; ++b) {
    const V32 x = block(d, X, b), y = block(d, Y, b);
    const int xa = (hn::GetLane(x) + 128) >> 16;
    const int ya = (std::min(hn::GetLane(y), hn::ExtractLane(y, 3)) + 128) >> 16;
    if (xa < 0 || kBytes * xa + 16 + kSlack > kBytes * src.width || ya < 0 || ya > src.height - 2) return false;
    bx[b] = 128 - xa * 65536, by[b] = 128 - ya * 65536, p[b] = src.row(ya) + kBytes * xa, ya_max = std::max(ya_max, ya);
  }
  rx = hn::ShiftRight<8>(hn::Add(X, per_block(d, bx)));
  ry = hn::ShiftRight<8>(hn::Add(Y, per_block(d, by)));
  const auto m1 = hn::Set(d, -1);
  if (!hn::AllTrue(d, hn::And(hn::And(hn::Gt(rx, m1), hn::Lt(rx, hn::Set(d, kRight * 256))),
                              hn::And(hn::Gt(ry, m1), hn::Lt(ry, hn::Set(d, 2 * 256))))))
    return false;
  straddle = !hn::AllTrue(d, hn::Lt(ry, hn::Set(d, 256)));
  return !(straddle && ya_max > src.height - 3);
}

// Four RGB24 pixels per block from the windows at p[b] (positions rx, ry relative to them,
// 1/256 px) to out[b], for the blocks whose bit in `skip` is clear: 12 bytes, A's 8 and B's
// first 4, packed by one lookup of A | B << 8 (lanes below 256).
constexpr Pattern kRgbBytes = per_block({0, 2, 4, 6, 8, 10, 12, 14, 1, 3, 5, 7, 0x80, 0x80, 0x80, 0x80});
template <class DB>
HWY_INLINE void rgb8_window_blend(DB d8, const SamplePlane& src, const std::uint8_t** p,
                                  hn::Vec<hn::Repartition<std::int32_t, DB>> rx, hn::Vec<hn::Repartition<std::int32_t, DB>> ry,
                                  bool straddle, std::uint8_t* const* out, unsigned skip) {
  const hn::Repartition<std::int32_t, DB> d;
  const auto i = hn::ShiftRight<8>(rx);
  const auto words = hn::BitCast(d8, hn::Or(hn::Or(hn::Add(i, hn::Add(i, i)), hn::ShiftLeft<8>(hn::And(rx, hn::Set(d, 255)))),
                                            hn::ShiftLeft<16>(ry)));
  const auto r0 = load_windows(d8, p);
  for (int b = 0; b < blocks_of<DB>(); ++b) p[b] += src.stride;
  const auto r1 = load_windows(d8, p);
  auto r2 = r1;
  if (straddle) {
    for (int b = 0; b < blocks_of<DB>(); ++b) p[b] += src.stride;
    r2 = load_windows(d8, p);
  }
  const auto a = rgb_half(d8, r0, r1, r2, straddle, words, kRgbPixelA, kRgbColourA);
  const auto c = rgb_half(d8, r0, r1, r2, straddle, words, kRgbPixelB, kRgbColourB);
  const auto v = hn::TableLookupBytesOr0(hn::BitCast(d8, hn::Or(a, hn::ShiftLeft<8>(c))), load_pattern(d8, kRgbBytes));
  const hn::Full64<std::uint8_t> d64;
  const hn::Full32<std::uint8_t> d32;
  for (int b = 0; b < blocks_of<DB>(); ++b) {
    if (skip >> b & 1) continue;
    const auto block16 = part<blocks_of<DB>(), D8>(d8, v, b);
    hn::StoreU(hn::LowerHalf(d64, block16), d64, out[b]);
    hn::StoreU(hn::LowerHalf(d32, hn::UpperHalf(d64, block16)), d32, out[b] + 8);
  }
}

// ---- U V pairs (NV12's chroma, YUYV's U V), four per block on 16-bit lanes ------------------
//
// One 16-byte window (8 pairs) per row and block from the block's first left tap, taken when
// its four taps lie within 6 samples right of it and one row below. Each sample's 32-bit lane
// splits into two 16-bit lanes, its U and its V: positions (below 2^16) are copied into the high
// half, and the lookup pattern 2i, 2i + 2, 2i + 1, 2i + 3 puts the U taps in the low lane and
// the V taps in the high one. YUYV's U V (kUV4) come from the even bytes of 32 (load_even_windows)
// and land on bytes 0 and 2 of each sample's four, merged with the luma between them (the same
// rows of which the same thread resamples, never at the same time).
//
// Four samples per block from the windows at p[b] (positions rx, ry relative to them, 1/256
// px) to out[b], for the blocks whose bit in `skip` is clear.
template <bool kUV4, class DB>
HWY_INLINE hn::Vec<hn::Repartition<std::uint16_t, DB>> pairs_blend(DB d8, const SamplePlane& src, const std::uint8_t** p,
                                                                 hn::Vec<hn::Repartition<std::int32_t, DB>> rx,
                                                                 hn::Vec<hn::Repartition<std::int32_t, DB>> ry, bool straddle) {
  const hn::Repartition<std::int32_t, DB> d;
  const hn::Repartition<std::uint16_t, DB> du16;
  rx = hn::Or(rx, hn::ShiftLeft<16>(rx)), ry = hn::Or(ry, hn::ShiftLeft<16>(ry));  // U and V lanes alike
  const auto x16 = hn::BitCast(du16, rx), y16 = hn::BitCast(du16, ry);
  const auto i2 = hn::ShiftLeft<1>(hn::ShiftRight<8>(x16));  // the left tap's first byte, per lane
  const auto idx = hn::BitCast(d8, hn::Add(hn::Or(i2, hn::ShiftLeft<8>(i2)), hn::BitCast(du16, hn::Set(d, 0x03010200))));
  const auto fx = hn::And(x16, hn::Set(du16, 255)), fy = hn::And(y16, hn::Set(du16, 255));
  hn::Vec<decltype(du16)> up, down;
  tap_pairs<kUV4>(d8, src, p, idx, straddle, hn::ShiftRight<8>(y16), up, down);
  return lerp16(blend_pairs(up, fx), blend_pairs(down, fx), fy);
}

template <bool kUV4, class DB>
HWY_INLINE void pairs_window_blend(DB d8, const SamplePlane& src, const std::uint8_t** p,
                                   hn::Vec<hn::Repartition<std::int32_t, DB>> rx, hn::Vec<hn::Repartition<std::int32_t, DB>> ry,
                                   bool straddle, std::uint8_t* const* out, unsigned skip) {
  const hn::Repartition<std::uint16_t, DB> du16;
  const auto v = pairs_blend<kUV4>(d8, src, p, rx, ry, straddle);
  if constexpr (kUV4)  // U V to bytes 0 and 2 of each sample's four, merged around the luma
    store_even_per_block(du16, v, out, skip);
  else
    store_per_block(du16, v, out, 0, 8, skip);
}

// ---- Four samples per block at any positions ----------------------------------------------
//
// RGB24 pixels, U V pairs, or YUYV's U V (windows of eight samples: 32 bytes from the block's
// first left tap, packed to eight U V pairs; the 32 bytes read and the 16 merged per block, the
// four samples and the luma byte after them, which the caller's room guarantees, stay inside the
// row: the plane starts one byte into it, block_windows' slack 16 + 1). Each block's origin read
// from its lanes, every lane checked; false (nothing written) when a block's taps do not fit.
enum class FourKind { kRgb24, kPairs, kYuyvUV };

template <FourKind kKind, class DB>
HWY_INLINE bool four_blocks(DB d8, const SamplePlane& src, hn::Vec<hn::Repartition<std::int32_t, DB>> X,
                            hn::Vec<hn::Repartition<std::int32_t, DB>> Y, std::uint8_t* const* out) {
  constexpr int kB = blocks_of<DB>();
  constexpr int kBytes = kKind == FourKind::kRgb24 ? 3 : kKind == FourKind::kPairs ? 2 : 4;
  constexpr int kRight = kKind == FourKind::kRgb24 ? 4 : 7;  // a window: 5 RGB24 pixels or 8 pairs
  const hn::Repartition<std::int32_t, DB> d;
  const std::uint8_t* p[kB];
  hn::Vec<decltype(d)> rx, ry;
  bool straddle = false;
  if (!block_windows<kBytes, kRight, kKind == FourKind::kYuyvUV ? 17 : 0>(d, src, X, Y, p, rx, ry, straddle)) return false;
  if constexpr (kKind == FourKind::kRgb24)
    rgb8_window_blend(d8, src, p, rx, ry, straddle, out, 0);
  else
    pairs_window_blend<kKind == FourKind::kYuyvUV>(d8, src, p, rx, ry, straddle, out, 0);
  return true;
}

// ---- Affine blocks of four samples: origins and checks in scalars ----------------------
//
// Block b of four samples lies in an affine cell segment: seg[b] is that segment and the index
// of the block's first sample in it. Each block's window origin, whether its taps fit the window
// and whether they straddle a row boundary come from the segment in scalars, as tap() rounds
// them (no per-lane checks): the positions are monotone along a segment, so its first and
// fourth sample bound the block's taps. A block that does not fit (its taps span more than
// kMaxTap samples, or lie near an edge) is sampled alone by four(), and left out of the windows.

struct BlockSegment {
  const Affine* a;
  int e;  // the block's first sample, from the segment's start
};

// Windows of kBytes-byte samples: origins p[b] and straddle; returns
// the blocks that do not fit, as bits (their window is a harmless one at the image's origin;
// the caller checks the plane is at least 16 bytes wide and 3 rows high).
template <int kBytes, int kMaxTap, int kB>
HWY_INLINE unsigned affine_block_windows(const SamplePlane& src, const BlockSegment* seg, const std::uint8_t** p,
                                         bool& straddle) {
  unsigned bad = 0;
  for (int b = 0; b < kB; ++b) {
    const Affine& a = *seg[b].a;
    const std::int64_t k = seg[b].e, x0 = a.ax + k * a.sx, x3 = x0 + 3 * std::int64_t{a.sx};
    const std::int64_t y0 = a.ay + k * a.sy, y3 = y0 + 3 * std::int64_t{a.sy};
    int xa = static_cast<int>((x0 + 128) >> 16), ya = static_cast<int>((std::min(y0, y3) + 128) >> 16);
    const std::int64_t xl = (x3 + 128) >> 16, yb = (std::max(y0, y3) + 128) >> 16;
    if (xa >= 0 && xl >= xa && xl - xa <= kMaxTap && kBytes * xa + 16 <= kBytes * src.width && ya >= 0 &&
        yb <= src.height - 2 && yb - ya <= 1)
      straddle |= yb != ya;
    else
      bad |= 1u << b, xa = 0, ya = 0;
    p[b] = src.row(ya) + kBytes * xa;
  }
  // When some block straddles, every block reads a third row: one whose rows end at the last
  // row goes alone too.
  if (straddle)
    for (int b = 0; b < kB; ++b)
      if (p[b] >= src.row(src.height - 2)) bad |= 1u << b, p[b] = src.data;
  return bad;
}

// Positions relative to each block's window origin in 1/256 px, the origin as mono8_relative
// takes it (the first sample's left tap, the upper of the first and fourth sample's top taps).
template <class D32x>
HWY_INLINE void block_relative(D32x d, hn::Vec<D32x> X, hn::Vec<D32x> Y, hn::Vec<D32x>& rx, hn::Vec<D32x>& ry) {
  const auto half = hn::Set(d, 128), whole = hn::Set(d, ~255);
  const auto x8 = hn::ShiftRight<8>(hn::Add(X, half)), y8 = hn::ShiftRight<8>(hn::Add(Y, half));
  rx = hn::Sub(x8, hn::And(hn::Broadcast<0>(x8), whole));
  ry = hn::Sub(y8, hn::And(hn::Min(hn::Broadcast<0>(y8), hn::Broadcast<3>(y8)), whole));
}

// A window holds 5 RGB24 pixels (left taps 0..3) or 8 U V pairs (left taps 0..6).
template <int C>
constexpr int kWindowTaps = C == 3 ? 3 : 6;

// RGB24 or U V pairs: four samples per block of affine segments, positions X, Y.
template <class T, int C, class DB>
HWY_INLINE void affine_blocks(DB d8, const SamplePlane& src, const BlockSegment* seg,
                              hn::Vec<hn::Repartition<std::int32_t, DB>> X, hn::Vec<hn::Repartition<std::int32_t, DB>> Y,
                              std::uint8_t* const* out) {
  constexpr int kB = blocks_of<DB>();
  const hn::Repartition<std::int32_t, DB> d;
  const std::uint8_t* p[kB];
  bool straddle = false;
  const unsigned bad = affine_block_windows<C * sizeof(T), kWindowTaps<C>, kB>(src, seg, p, straddle);
  for (int b = 0; b < kB; ++b)
    if (bad >> b & 1) four<T, C>(src, block(d, X, b), block(d, Y, b), out[b], false);
  if (bad == (1u << kB) - 1) return;
  // Relative to the origins as mono8_relative computes them: the same as p[b] for the blocks
  // that fit.
  hn::Vec<decltype(d)> rx, ry;
  block_relative(d, X, Y, rx, ry);
  if constexpr (C == 3)
    rgb8_window_blend(d8, src, p, rx, ry, straddle, out, bad);
  else
    pairs_window_blend<false>(d8, src, p, rx, ry, straddle, out, bad);
}

#endif  // HWY_TARGET != HWY_SCALAR
// NOLINTNEXTLINE(google-readability-namespace-comments)
}  // namespace HWY_NAMESPACE
}  // namespace rsd::dsp::rectify_detail
HWY_AFTER_NAMESPACE();
#endif  // RSD_DSP_RECTIFY_BILINEAR_FOUR_BLOCKS_INL_H_
