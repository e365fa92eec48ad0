// The bilinear sampler's SIMD kernels, part 2: "wide steps" of one, two or four 128-bit blocks
// with the windows, blends and stores that every block kernel on 16-bit lanes shares, and
// Mono8's block kernel (8 pixels per block, at any positions or along affine segments). RGB24's
// and U V pairs' blocks of four live in bilinear_four_blocks-inl.h.
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

#endif  // HWY_TARGET != HWY_SCALAR
// NOLINTNEXTLINE(google-readability-namespace-comments)
}  // namespace HWY_NAMESPACE
}  // namespace rsd::dsp::rectify_detail
HWY_AFTER_NAMESPACE();
#endif  // RSD_DSP_RECTIFY_BILINEAR_BLOCKS_INL_H_
