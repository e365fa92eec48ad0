// The bilinear sampler's SIMD kernels, part 2: "wide steps" of one, two or four 128-bit blocks,
// and the block kernels on 16-bit lanes of Mono8 (8 pixels per block), RGB24 and U V pairs (4
// samples per block, at any positions or along affine segments with per-block checks).
// Included by bilinear_sampling_simd.cpp once per Highway target, after bilinear_four-inl.h.
#if defined(RSD_DSP_RECTIFY_BILINEAR_BLOCKS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef RSD_DSP_RECTIFY_BILINEAR_BLOCKS_INL_H_
#undef RSD_DSP_RECTIFY_BILINEAR_BLOCKS_INL_H_
#else
#define RSD_DSP_RECTIFY_BILINEAR_BLOCKS_INL_H_
#endif

#include <algorithm>
#include <cstdlib>
#include <cstring>

#include "hwy/highway.h"
#include "dsp/rectify/bilinear_sampling.hpp"

HWY_BEFORE_NAMESPACE();
namespace rsd::dsp::rectify_detail {
namespace HWY_NAMESPACE {
#if HWY_TARGET != HWY_SCALAR
namespace hn = hwy::HWY_NAMESPACE;

// ---- Wide steps: as many 128-bit blocks as the target's vectors hold, up to four ----------------
//
// AVX2 runs two blocks per instruction (256-bit vectors), AVX-512 four, the others one (SVE: one
// 128-bit block whatever its vector length, since windows are per block). A wide step is 8
// pixels per block: positions X0 hold pixels 8b..8b+3 in block b, X1 pixels 8b+4..8b+7, so
// that narrowing the two to 16 bits per block (packssdw on x86) puts each block's 8 pixels in
// order in that block, with no lane crossing.
#if HWY_HAVE_SCALABLE
using DW16 = hn::Full128<std::int16_t>;
#else
using DW16 = hn::CappedTag<std::int16_t, 32>;
#endif
using DWU16 = hn::RebindToUnsigned<DW16>;
using DW32 = hn::Repartition<std::int32_t, DW16>;
using DW8 = hn::Repartition<std::uint8_t, DW16>;
using VW32 = hn::Vec<DW32>;
constexpr int kBlocks = static_cast<int>(hn::MaxLanes(DW16()) / 8);
constexpr int kStep = 8 * kBlocks;
constexpr int kStepShift = kBlocks == 1 ? 3 : kBlocks == 2 ? 4 : 5;  // kStep = 1 << kStepShift
static_assert(kBlocks == 1 || kBlocks == 2 || kBlocks == 4, "one, two or four 128-bit blocks per step");

// A 16-byte lookup pattern, the same in every 128-bit block, laid out over the widest step (four
// blocks): one full-width load gives it to every block, and the lookup that uses it takes the
// load as its memory operand. (A 16-byte pattern broadcast by LoadDup128 was hoisted out of the
// loops as 16 bytes and broadcast again by a shuffle in every step: ~5 % of the U V pairs
// kernel's time on AVX-512, whose shuffles are its bottleneck.)
struct alignas(64) Pattern {
  std::uint8_t b[64] = {};
};
constexpr Pattern per_block(const std::uint8_t (&p)[16]) {
  Pattern r;
  for (int i = 0; i < 64; ++i) r.b[i] = p[i % 16];
  return r;
}
template <class D>
HWY_INLINE hn::Vec<D> load_pattern(D d8, const Pattern& p) {
  return hn::Load(d8, p.b);
}

// The helpers below take a vector of 1, 2 or 4 blocks (tag D) and recurse on its halves; they
// are templates on the tag, so that `if constexpr` discards the branches of other widths.
template <class D>
constexpr int blocks_of() {
  return static_cast<int>(hn::MaxLanes(D()) * sizeof(hn::TFromD<D>) / 16);
}

// Part b of the kParts equal parts of v (tag D), each of tag P. kParts comes from a tag whose
// lane count is fixed (on SVE a half-width tag's MaxLanes is not simply half its parent's; there
// every vector type of a lane type is the same sizeless type, so one part is v itself).
template <int kParts, class P, class D>
HWY_INLINE hn::Vec<P> part(D d, hn::Vec<D> v, int b) {
  if constexpr (kParts == 1) {
    (void)d, (void)b;
    return v;
  } else {
    const hn::Half<D> dh;
    constexpr int kHalf = kParts / 2;
    return b < kHalf ? part<kHalf, P>(dh, hn::LowerHalf(dh, v), b) : part<kHalf, P>(dh, hn::UpperHalf(dh, v), b - kHalf);
  }
}

// The four int32 lanes of block b.
template <class D>
HWY_INLINE V32 block(D d, hn::Vec<D> v, int b) {
  return part<blocks_of<D>(), D32>(d, v, b);
}

// The vector whose block b holds v[b] in every lane.
template <class D>
HWY_INLINE hn::Vec<D> per_block(D d, const int* v) {
  if constexpr (blocks_of<D>() == 1) {
    return hn::Set(d, v[0]);
  } else {
    const hn::Half<D> dh;
    return hn::Combine(d, per_block(dh, v + blocks_of<D>() / 2), per_block(dh, v));
  }
}

// Block b loaded from p[b] (16 bytes each).
template <class D>
HWY_INLINE hn::Vec<D> load_windows(D d, const std::uint8_t* const* p) {
  if constexpr (blocks_of<D>() == 1) {
    return hn::LoadU(d, p[0]);
  } else {
    const hn::Half<D> dh;
    return hn::Combine(d, load_windows(dh, p + blocks_of<D>() / 2), load_windows(dh, p));
  }
}

// 32 -> 16 bits, saturating, block b of the result = block b of lo then block b of hi.
template <class D32x>
HWY_INLINE hn::Vec<hn::Repartition<std::int16_t, D32x>> narrow_blocks(D32x, hn::Vec<D32x> lo, hn::Vec<D32x> hi) {
#if HWY_HAVE_SCALABLE
  return narrow(lo, hi);  // one block; SVE's ReorderDemote2To interleaves the two
#else
  return hn::ReorderDemote2To(hn::Repartition<std::int16_t, D32x>(), lo, hi);  // packssdw per block on x86
#endif
}

// (p0 (256 - f) + p1 f + 128) >> 8 on 16-bit lanes, 8-bit pixels and weights. It equals
// p0 + floor(((p1 - p0) f + 128) / 256) = p0 + floor(((p1 - p0) (f << 7) + 2^14) / 2^15): one
// rounding multiply-high (pmulhrsw, vqrdmulh) of the signed difference, |p1 - p0| (f << 7) being
// far from its one saturating case.
template <class V>
HWY_INLINE V lerp16(V p0, V p1, V f) {
  const hn::DFromV<V> d;
  const hn::RebindToSigned<decltype(d)> di;
  const auto step = hn::MulFixedPoint15(hn::BitCast(di, hn::Sub(p1, p0)), hn::BitCast(di, hn::ShiftLeft<7>(f)));
  return hn::Add(p0, hn::BitCast(d, step));
}

// The horizontal blend of 16-bit lanes holding byte pairs (p0 low, p1 high).
template <class V>
HWY_INLINE V blend_pairs(V pairs, V f) {
  const hn::DFromV<V> d;
  return lerp16(hn::And(pairs, hn::Set(d, 0xFF)), hn::ShiftRight<8>(pairs), f);
}

// The even bytes of 32 from p[b], as one 16-byte window per block: the samples of a plane whose
// samples are two bytes apart (YUYV's luma, an 8-bit mosaic's sites: 16 samples), or YUYV's U V
// from a sample's U (its V two bytes on, the next sample's U four: eight U V pairs, the layout
// of an NV12 chroma window). Two 16-byte loads per block.
constexpr Pattern kEvenBytes = per_block({0, 2, 4, 6, 8, 10, 12, 14, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80, 0x80});
template <class D>
HWY_INLINE hn::Vec<D> load_even_windows(D d8, const std::uint8_t* const* p) {
  const std::uint8_t* q[blocks_of<D>()];
  for (int b = 0; b < blocks_of<D>(); ++b) q[b] = p[b] + 16;
  const auto even = load_pattern(d8, kEvenBytes);
  const hn::Repartition<std::uint64_t, D> d64;
  return hn::BitCast(d8, hn::InterleaveLower(d64, hn::BitCast(d64, hn::TableLookupBytesOr0(load_windows(d8, p), even)),
                                             hn::BitCast(d64, hn::TableLookupBytesOr0(load_windows(d8, q), even))));
}

// A row's window per block: 16 bytes, or the even bytes of 32 (kEven).
template <bool kEven, class D>
HWY_INLINE hn::Vec<D> row_windows(D d8, const std::uint8_t* const* p) {
  if constexpr (kEven)
    return load_even_windows(d8, p);
  else
    return load_windows(d8, p);
}

// Bytes v (8 per block, the result of a block's 16-bit lanes) to the even bytes of the 16 at
// out[b], merged with the odd ones there (another plane's samples), for the blocks whose bit in
// skip is clear.
template <class DU16x>
HWY_INLINE void store_even_per_block(DU16x, hn::Vec<DU16x> v, std::uint8_t* const* out, unsigned skip = 0) {
  constexpr int kB = blocks_of<DU16x>();
  const hn::Rebind<std::uint8_t, DU16x> d8n;
  const auto bytes = hn::DemoteTo(d8n, hn::BitCast(hn::RebindToSigned<DU16x>(), v));
  const hn::Full64<std::uint8_t> d64;
  const hn::Full128<std::uint16_t> w16;
  const hn::Full128<std::uint8_t> w8;
  for (int b = 0; b < kB; ++b) {
    if (skip >> b & 1) continue;
    const auto ours = hn::BitCast(w8, hn::PromoteTo(w16, part<kB, decltype(d64)>(d8n, bytes, b)));
    const auto others = hn::And(hn::LoadU(w8, out[b]), hn::BitCast(w8, hn::Set(w16, 0xFF00)));
    hn::StoreU(hn::Or(others, ours), w8, out[b]);
  }
}

// The tap pairs of every 16-bit lane on its two rows, up and down, looked up by idx (0x80: zero)
// in the blocks' windows at p[b] (advanced past the rows read): rows ya and ya + 1, or, for the
// lanes whose `lower` is 1 when the taps straddle a row boundary, ya + 1 and ya + 2.
template <bool kEven = false, class DB, class VU>
HWY_INLINE void tap_pairs(DB d8, const SamplePlane& src, const std::uint8_t** p, hn::Vec<DB> idx, bool straddle, VU lower,
                          VU& up, VU& down) {
  const hn::DFromV<VU> du16;
  const auto r0 = row_windows<kEven>(d8, p);
  for (int b = 0; b < blocks_of<DB>(); ++b) p[b] += src.stride;
  up = hn::BitCast(du16, hn::TableLookupBytesOr0(r0, idx));
  down = hn::BitCast(du16, hn::TableLookupBytesOr0(row_windows<kEven>(d8, p), idx));
  if (!straddle) return;
  for (int b = 0; b < blocks_of<DB>(); ++b) p[b] += src.stride;
  const auto m = hn::Eq(lower, hn::Set(du16, 1));
  up = hn::IfThenElse(m, down, up);
  down = hn::IfThenElse(m, hn::BitCast(du16, hn::TableLookupBytesOr0(row_windows<kEven>(d8, p), idx)), down);
}

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

// ---- Mono8, eight pixels per block on 16-bit lanes ----------------------------------------
//
// One 16-byte window per row and block from the block's first left tap, taken when its eight
// taps lie within 14 px right of it and one row below. Positions are rounded to 1/256 px relative
// to the window (tap offset in the high byte, weight in the low byte of a 16-bit lane: inside a
// window they are below 15 x 256, and the saturating narrowing keeps anything further out of
// range); byte pairs (p0, p1) come out of the windows by lookup and blend on 16-bit lanes.

// The positions relative to each block's window origin, narrowed to 16 bits: the origin is
// (xa, ya) = (the block's first left tap, the upper of its first and last pixel's top taps), as
// tap() rounds them; in 1/256 px that is lane 0 of (X0 + 128) >> 8, and the smaller of lane 0
// of (Y0 + 128) >> 8 and lane 3 of (Y1 + 128) >> 8, each rounded down to whole pixels
// (Broadcast: per 128-bit block, no lane crossing).
template <class D16x>
HWY_INLINE void mono8_relative(D16x, hn::Vec<hn::Repartition<std::int32_t, D16x>> X0,
                               hn::Vec<hn::Repartition<std::int32_t, D16x>> Y0, hn::Vec<hn::Repartition<std::int32_t, D16x>> X1,
                               hn::Vec<hn::Repartition<std::int32_t, D16x>> Y1, hn::Vec<hn::RebindToUnsigned<D16x>>& rx,
                               hn::Vec<hn::RebindToUnsigned<D16x>>& ry) {
  const hn::Repartition<std::int32_t, D16x> d32;
  const hn::RebindToUnsigned<D16x> du16;
  const auto half = hn::Set(d32, 128), whole = hn::Set(d32, ~255);
  const auto x0 = hn::ShiftRight<8>(hn::Add(X0, half)), x1 = hn::ShiftRight<8>(hn::Add(X1, half));
  const auto y0 = hn::ShiftRight<8>(hn::Add(Y0, half)), y1 = hn::ShiftRight<8>(hn::Add(Y1, half));
  const auto xa = hn::And(hn::Broadcast<0>(x0), whole);
  const auto ya = hn::And(hn::Min(hn::Broadcast<0>(y0), hn::Broadcast<3>(y1)), whole);
  rx = hn::BitCast(du16, narrow_blocks(d32, hn::Sub(x0, xa), hn::Sub(x1, xa)));
  ry = hn::BitCast(du16, narrow_blocks(d32, hn::Sub(y0, ya), hn::Sub(y1, ya)));
}

// The taps looked up in the windows at rows ya[b] (and the next one or two) and blended.
// kEven: samples two bytes apart (mono8_blocks).
template <bool kEven, class D16x>
HWY_INLINE void mono8_blend(D16x d16, const SamplePlane& src, const int* xa, const int* ya,
                            hn::Vec<hn::RebindToUnsigned<D16x>> rx, hn::Vec<hn::RebindToUnsigned<D16x>> ry, bool straddle,
                            std::uint8_t* out) {
  const hn::RebindToUnsigned<D16x> du16;
  const hn::Repartition<std::uint8_t, D16x> d8;
  using VU = hn::Vec<decltype(du16)>;
  constexpr int kB = blocks_of<D16x>();
  const std::uint8_t* p[kB];
  for (int b = 0; b < kB; ++b) p[b] = src.row(ya[b]) + (kEven ? 2 : 1) * xa[b];
  const VU i = hn::ShiftRight<8>(rx), lower = hn::ShiftRight<8>(ry);
  const VU fx = hn::And(rx, hn::Set(du16, 0xFF)), fy = hn::And(ry, hn::Set(du16, 0xFF));
  const auto idx = hn::BitCast(d8, hn::Or(i, hn::ShiftLeft<8>(hn::Add(i, hn::Set(du16, 1)))));
  VU up, down;
  tap_pairs<kEven>(d8, src, p, idx, straddle, lower, up, down);
  const VU v = lerp16(blend_pairs(up, fx), blend_pairs(down, fx), fy);
  if constexpr (kEven) {
    std::uint8_t* o[kB];
    for (int b = 0; b < kB; ++b) o[b] = out + 16 * b;
    store_even_per_block(du16, v, o);
  } else {
    const hn::Rebind<std::uint8_t, D16x> d8n;
    hn::StoreU(hn::DemoteTo(d8n, hn::BitCast(d16, v)), d8n, out);
  }
}

// The last window origin whose reads stay in the row: 16 bytes, or 32 from a plane of samples
// two bytes apart that may start one byte into its row.
template <bool kEven>
HWY_INLINE int last_origin(const SamplePlane& src) {
  return kEven ? src.width - 17 : src.width - 16;
}

// Any positions: each block's origin read from its lanes, every lane checked; false (nothing
// written) when a block's taps do not fit its windows. kEven: samples two bytes apart (YUYV's
// luma, an 8-bit mosaic's sites), written to every other byte of out, merged with the bytes
// between (the other planes': 16 bytes per block, the last one the caller's room).
template <bool kEven = false, class D16x>
HWY_INLINE bool mono8_blocks(D16x d16, const SamplePlane& src, hn::Vec<hn::Repartition<std::int32_t, D16x>> X0,
                             hn::Vec<hn::Repartition<std::int32_t, D16x>> Y0, hn::Vec<hn::Repartition<std::int32_t, D16x>> X1,
                             hn::Vec<hn::Repartition<std::int32_t, D16x>> Y1, std::uint8_t* out) {
  constexpr int kB = blocks_of<D16x>();
  const hn::Repartition<std::int32_t, D16x> d32;
  const hn::RebindToUnsigned<D16x> du16;
  int xa[kB], ya[kB], ya_max = 0;
  for (int b = 0; b < kB; ++b) {
    const V32 x0 = block(d32, X0, b), y0 = block(d32, Y0, b), y1 = block(d32, Y1, b);
    xa[b] = (hn::GetLane(x0) + 128) >> 16;  // the block's first left tap, as tap() rounds
    ya[b] = (std::min(hn::GetLane(y0), hn::ExtractLane(y1, 3)) + 128) >> 16;
    if (xa[b] < 0 || xa[b] > last_origin<kEven>(src) || ya[b] < 0 || ya[b] > src.height - 2) return false;
    ya_max = std::max(ya_max, ya[b]);
  }
  hn::Vec<decltype(du16)> rx, ry;
  mono8_relative(d16, X0, Y0, X1, Y1, rx, ry);
  const auto fits = hn::And(hn::Lt(hn::BitCast(d16, rx), hn::Set(d16, 15 * 256)),
                            hn::Lt(hn::BitCast(d16, ry), hn::Set(d16, 2 * 256)));
  const auto ahead = hn::And(hn::Gt(hn::BitCast(d16, rx), hn::Set(d16, -1)), hn::Gt(hn::BitCast(d16, ry), hn::Set(d16, -1)));
  if (!hn::AllTrue(d16, hn::And(fits, ahead))) return false;
  const bool straddle = !hn::AllTrue(du16, hn::Lt(ry, hn::Set(du16, 256)));
  if (straddle && ya_max > src.height - 3) return false;
  mono8_blend<kEven>(d16, src, xa, ya, rx, ry, straddle, out);
  return true;
}

// The window origins of `count` blocks of eight samples of an affine segment known to fit
// (affine_fits, blocks8_fit), the blocks at samples e0, e0 + 8, ...: each block's first left
// tap and the upper of its first and last sample's top taps, as tap() rounds them; straddle is
// set when some block's taps straddle a row boundary. Running sums: the positions of a segment
// that fits lie inside the image, so they neither wrap nor differ from the lanes'.
HWY_INLINE void segment_origins(const Affine& a, int e0, int count, int* xa, int* ya, bool& straddle) {
  const std::int64_t span = 7 * std::int64_t{a.sy};
  const std::int64_t top = std::min<std::int64_t>(0, span), bottom = std::max<std::int64_t>(0, span);
  std::int64_t x = a.ax + std::int64_t{e0} * a.sx + 128, y = a.ay + std::int64_t{e0} * a.sy + 128;
  for (int m = 0; m < count; ++m, x += 8 * std::int64_t{a.sx}, y += 8 * std::int64_t{a.sy}) {
    xa[m] = static_cast<int>(x >> 16);
    ya[m] = static_cast<int>((y + top) >> 16);
    straddle = straddle || ((y + bottom) >> 16) != ya[m];
  }
}

// Blocks of affine segments known to fit, origins given (segment_origins): the same integers as
// mono8_blocks without its per-lane checks.
template <bool kEven, class D16x>
HWY_INLINE void mono8_affine_blocks(D16x d16, const SamplePlane& src, const int* xa, const int* ya, bool straddle,
                                    hn::Vec<hn::Repartition<std::int32_t, D16x>> X0, hn::Vec<hn::Repartition<std::int32_t, D16x>> Y0,
                                    hn::Vec<hn::Repartition<std::int32_t, D16x>> X1, hn::Vec<hn::Repartition<std::int32_t, D16x>> Y1,
                                    std::uint8_t* out) {
  const hn::RebindToUnsigned<D16x> du16;
  hn::Vec<decltype(du16)> rx, ry;
  mono8_relative(d16, X0, Y0, X1, Y1, rx, ry);
  mono8_blend<kEven>(d16, src, xa, ya, rx, ry, straddle, out);
}

// Whether every block of kStep-pixel steps over pixels [0, n) of segment a fits its windows
// without checks: the taps move right by at most 1.75 px a pixel (a block's eight span at most
// 13.25 px of a 16-byte window) and by less than 1/8 row a pixel (at most two rows), and every
// tap of the segment lies at least 16 px from the right edge and 3 rows from the bottom.
template <bool kEven>
inline bool affine_fits(const SamplePlane& src, const Affine& a, int n) {
  return segment_within(a, n, 7 * 65536 / 4 + 1, last_origin<kEven>(src), src.height - 3);
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
#endif  // RSD_DSP_RECTIFY_BILINEAR_BLOCKS_INL_H_
