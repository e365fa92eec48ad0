// The SIMD kernels of the bilinear sampler, one source for every instruction set: Google
// Highway compiles this file once per target (SSSE3, SSE4, AVX2, AVX-512 and its portable
// EMU128 on x86-64; NEON, SVE and SVE2 on arm64) and picks the best the CPU runs at run time.
// Every kernel computes the integers of the scalar reference (bilinear_sampling.hpp) bit for
// bit; tests/dsp/rectify/test_bilinear_sampling.cpp compares each target with it.
//
// The taps are fetched by byte lookups inside 16-byte windows of the source rows, which every
// instruction set does per 128-bit block; so the kernels work in 128-bit blocks, two per vector
// where the target has 256 bits or more at a fixed width (AVX2, AVX-512: "wide steps"), one
// elsewhere (SSE, NEON, EMU128, and SVE whatever its vector length). Per block:
// - Mono8: 8 pixels through one window per row (two rows, three where the taps straddle a row
//   boundary), blended on 16-bit lanes (mono8_blocks);
// - RGB24: 4 pixels through one 5-pixel window per row, each output byte a 16-bit lane that
//   looks up its own colour's tap pair (rgb8_blocks);
// - otherwise (Mono16, steps whose taps do not fit a window) 4 pixels on 32-bit lanes: windows
//   where the taps fit, else a gather of the 32-bit word at each left tap (it holds the right tap
//   too: bytes 0..1 for Mono8, both halves for Mono16; RGB24 gathers again at +3), only when all
//   four taps are at least 3 px inside the right edge so that the reads never leave the row.
// Steps entirely outside the image store zeros; the rest (near the borders) go to the scalar
// pixel code. Pixels are little-endian in memory (x86-64 and arm64).
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "dsp/rectify/bilinear_sampling_simd.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep (before highway.h)
#include "hwy/highway.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "dsp/rectify/bilinear_sampling.hpp"

HWY_BEFORE_NAMESPACE();
namespace rsd::dsp::rectify_detail {
namespace HWY_NAMESPACE {

// Highway's HWY_SCALAR target (an x86-64 CPU without SSSE3) has one-lane vectors only: there
// the kernels are the scalar reference itself.
#if HWY_TARGET == HWY_SCALAR
Samplers simd_samplers(PixelFormat f) { return scalar_samplers(f); }
#else
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
constexpr std::uint32_t kWordPattern = sizeof(T) == 2 ? 0x03020100u : (C == 3 ? 0x80020100u : 0x80800100u);

HWY_INLINE V32 gather_row(const std::uint8_t* row0, V32 off) {
  const D32 d;
  return hn::GatherOffset(d, reinterpret_cast<const std::int32_t*>(row0), off);
}

template <class T, int C>
HWY_INLINE void gather_words(const ImageView& src, V32 x0, V32 y0, V32& top, V32& bot, V32& top_r, V32& bot_r) {
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
HWY_INLINE bool window_words(const ImageView& src, V32 x0, V32 y0, V32& top, V32& bot, V32& top_r, V32& bot_r) {
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
HWY_INLINE void four(const ImageView& src, V32 X, V32 Y, std::uint8_t* out, bool room) {
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
  if (k < 0) return static_cast<void>(std::memset(out, 0, 4 * C * sizeof(T)));
  alignas(16) std::int32_t xs[4], ys[4];
  hn::Store(X, d, xs), hn::Store(Y, d, ys);
  sample_row_scalar<T, C>(src, xs, ys, out, 4);
}


// 32 -> 16 bits, saturating, in order (lo's lanes, then hi's).
HWY_INLINE hn::Vec<D16> narrow(V32 lo, V32 hi) {
  const hn::Full64<std::int16_t> dh;
  return hn::Combine(D16(), hn::DemoteTo(dh, hi), hn::DemoteTo(dh, lo));
}

// ---- Wide steps: as many 128-bit blocks as the target's vectors hold, up to two ---------------
//
// AVX2 and AVX-512 run two blocks per instruction (256-bit vectors), the others one (SVE: one
// 128-bit block whatever its vector length, since windows are per block). A wide step is 8
// pixels per block: positions X0 hold pixels 8b..8b+3 in block b, X1 pixels 8b+4..8b+7, so
// that narrowing the two to 16 bits per block (packssdw on x86) puts each block's 8 pixels in
// order in that block, with no lane crossing.
#if HWY_HAVE_SCALABLE
using DW16 = hn::Full128<std::int16_t>;
#else
using DW16 = hn::CappedTag<std::int16_t, 16>;
#endif
using DWU16 = hn::RebindToUnsigned<DW16>;
using DW32 = hn::Repartition<std::int32_t, DW16>;
using DW8 = hn::Repartition<std::uint8_t, DW16>;
using VW32 = hn::Vec<DW32>;
constexpr int kBlocks = static_cast<int>(hn::MaxLanes(DW16()) / 8);
constexpr int kStep = 8 * kBlocks;
static_assert(kBlocks == 1 || kBlocks == 2, "one or two 128-bit blocks per step");

// 128-bit blocks in a vector of tag D (1 or 2). The helpers below are templates on the tag, so
// that `if constexpr` discards the branch of the other width.
template <class D>
constexpr int blocks_of() {
  return static_cast<int>(hn::MaxLanes(D()) * sizeof(hn::TFromD<D>) / 16);
}

// The four int32 lanes of block b.
template <class D>
HWY_INLINE V32 block(D, hn::Vec<D> v, int b) {
  if constexpr (blocks_of<D>() == 1) {
    return v;
  } else {
    const hn::Half<D> dh;
    return b == 0 ? hn::LowerHalf(dh, v) : hn::UpperHalf(dh, v);
  }
}

// The vector whose block b holds v[b] in every lane.
template <class D>
HWY_INLINE hn::Vec<D> per_block(D d, const int* v) {
  if constexpr (blocks_of<D>() == 1)
    return hn::Set(d, v[0]);
  else
    return hn::ConcatLowerLower(d, hn::Set(d, v[1]), hn::Set(d, v[0]));
}

// Block b loaded from p[b] (16 bytes each).
template <class D>
HWY_INLINE hn::Vec<D> load_windows(D d, const std::uint8_t* const* p) {
  if constexpr (blocks_of<D>() == 1) {
    return hn::LoadU(d, p[0]);
  } else {
    const hn::Half<D> dh;
    return hn::Combine(d, hn::LoadU(dh, p[1]), hn::LoadU(dh, p[0]));
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

// (p0 (256 - f) + p1 f + 128) >> 8 on 16-bit lanes: for 8-bit pixels every term fits.
template <class V>
HWY_INLINE V lerp16(V p0, V p1, V f) {
  const hn::DFromV<V> d;
  return hn::ShiftRight<8>(hn::Add(hn::Add(hn::Mul(p0, hn::Sub(hn::Set(d, 256), f)), hn::Mul(p1, f)), hn::Set(d, 128)));
}

// The horizontal blend of 16-bit lanes holding byte pairs (p0 low, p1 high).
template <class V>
HWY_INLINE V blend_pairs(V pairs, V f) {
  const hn::DFromV<V> d;
  return lerp16(hn::And(pairs, hn::Set(d, 0xFF)), hn::ShiftRight<8>(pairs), f);
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
alignas(16) constexpr std::uint8_t kRgbPixelA[16] = {0, 0, 0, 0, 0, 0, 4, 4, 4, 4, 4, 4, 8, 8, 8, 8};
alignas(16) constexpr std::uint8_t kRgbPixelB[16] = {8, 8, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12, 12};
alignas(16) constexpr std::uint8_t kRgbColourA[16] = {0, 3, 1, 4, 2, 5, 0, 3, 1, 4, 2, 5, 0, 3, 1, 4};
alignas(16) constexpr std::uint8_t kRgbColourB[16] = {2, 5, 0, 3, 1, 4, 2, 5, 0, 3, 0, 3, 0, 3, 0, 3};

// Byte `offset` of each lane's pixel word into the lane's low byte (high byte zero).
template <class DB>
HWY_INLINE hn::Vec<hn::Repartition<std::uint16_t, DB>> spread(DB d8, hn::Vec<DB> words, const std::uint8_t* pixel,
                                                            int offset) {
  const hn::Repartition<std::uint16_t, DB> du16;
  const auto sel = hn::Add(hn::LoadDup128(d8, pixel), hn::BitCast(d8, hn::Set(du16, static_cast<std::uint16_t>(offset | 0x8000))));
  return hn::BitCast(du16, hn::TableLookupBytesOr0(words, sel));
}

// The blend of A or B (by its lookup patterns) in every block.
template <class DB>
HWY_INLINE hn::Vec<hn::Repartition<std::uint16_t, DB>> rgb_half(DB d8, hn::Vec<DB> r0, hn::Vec<DB> r1, hn::Vec<DB> r2,
                                                              bool straddle, hn::Vec<DB> words, const std::uint8_t* pixel,
                                                              const std::uint8_t* colour) {
  const hn::Repartition<std::uint16_t, DB> du16;
  using VU = hn::Vec<decltype(du16)>;
  const auto idx = hn::Add(hn::TableLookupBytes(words, hn::LoadDup128(d8, pixel)), hn::LoadDup128(d8, colour));
  const VU fx = spread(d8, words, pixel, 1), fy = spread(d8, words, pixel, 2);
  VU up = hn::BitCast(du16, hn::TableLookupBytes(r0, idx)), down = hn::BitCast(du16, hn::TableLookupBytes(r1, idx));
  if (straddle) {
    const auto m = hn::Eq(spread(d8, words, pixel, 3), hn::Set(du16, 1));
    up = hn::IfThenElse(m, down, up);
    down = hn::IfThenElse(m, hn::BitCast(du16, hn::TableLookupBytes(r2, idx)), down);
  }
  return lerp16(blend_pairs(up, fx), blend_pairs(down, fx), fy);
}

// Bytes [0, n) of each block's 16-bit lanes, narrowed, to out[b] + at (n: 4 or 8).
template <class DU16x>
HWY_INLINE void store_per_block(DU16x, hn::Vec<DU16x> v, std::uint8_t* const* out, int at, int n) {
  const hn::Rebind<std::uint8_t, DU16x> d8n;
  const auto bytes = hn::DemoteTo(d8n, hn::BitCast(hn::RebindToSigned<DU16x>(), v));
  const hn::Full64<std::uint8_t> d64;
  const hn::Full32<std::uint8_t> d32;
  for (int b = 0; b < blocks_of<DU16x>(); ++b) {
    hn::Vec<decltype(d64)> half;
    if constexpr (blocks_of<DU16x>() == 1)
      half = bytes;
    else
      half = b == 0 ? hn::LowerHalf(d64, bytes) : hn::UpperHalf(d64, bytes);
    if (n == 8)
      hn::StoreU(half, d64, out[b] + at);
    else
      hn::StoreU(hn::LowerHalf(d32, half), d32, out[b] + at);
  }
}

// Four pixels per block (positions X, Y) to out[b].
template <class DB>
HWY_INLINE bool rgb8_blocks(DB d8, const ImageView& src, hn::Vec<hn::Repartition<std::int32_t, DB>> X,
                            hn::Vec<hn::Repartition<std::int32_t, DB>> Y, std::uint8_t* const* out) {
  constexpr int kB = blocks_of<DB>();
  const hn::Repartition<std::int32_t, DB> d;
  const hn::Repartition<std::uint16_t, DB> du16;
  int bx[kB], by[kB], ya_max = 0;
  const std::uint8_t* p[kB];
  for (int b = 0; b < kB; ++b) {
    const V32 x = block(d, X, b), y = block(d, Y, b);
    const int xa = (hn::GetLane(x) + 128) >> 16;
    const int ya = (std::min(hn::GetLane(y), hn::ExtractLane(y, 3)) + 128) >> 16;
    if (xa < 0 || 3 * xa + 16 > 3 * src.width || ya < 0 || ya > src.height - 2) return false;
    bx[b] = 128 - xa * 65536, by[b] = 128 - ya * 65536, p[b] = src.row(ya) + 3 * xa, ya_max = std::max(ya_max, ya);
  }
  const auto rx = hn::ShiftRight<8>(hn::Add(X, per_block(d, bx)));
  const auto ry = hn::ShiftRight<8>(hn::Add(Y, per_block(d, by)));
  const auto m1 = hn::Set(d, -1);
  if (!hn::AllTrue(d, hn::And(hn::And(hn::Gt(rx, m1), hn::Lt(rx, hn::Set(d, 4 * 256))),
                              hn::And(hn::Gt(ry, m1), hn::Lt(ry, hn::Set(d, 2 * 256))))))
    return false;
  const bool straddle = !hn::AllTrue(d, hn::Lt(ry, hn::Set(d, 256)));
  if (straddle && ya_max > src.height - 3) return false;
  const auto i = hn::ShiftRight<8>(rx);
  const auto words = hn::BitCast(d8, hn::Or(hn::Or(hn::Add(i, hn::Add(i, i)), hn::ShiftLeft<8>(hn::And(rx, hn::Set(d, 255)))),
                                            hn::ShiftLeft<16>(ry)));
  const auto r0 = load_windows(d8, p);
  for (auto& q : p) q += src.stride;
  const auto r1 = load_windows(d8, p);
  auto r2 = r1;
  if (straddle) {
    for (auto& q : p) q += src.stride;
    r2 = load_windows(d8, p);
  }
  store_per_block(du16, rgb_half(d8, r0, r1, r2, straddle, words, kRgbPixelA, kRgbColourA), out, 0, 8);
  store_per_block(du16, rgb_half(d8, r0, r1, r2, straddle, words, kRgbPixelB, kRgbColourB), out, 8, 4);
  return true;
}

// ---- Mono8, eight pixels per block on 16-bit lanes ----------------------------------------
//
// One 16-byte window per row and block from the block's first left tap, taken when its eight
// taps lie within 14 px right of it and one row below. Positions are rounded to 1/256 px relative
// to the window (tap offset in the high byte, weight in the low byte of a 16-bit lane: inside a
// window they are below 15 x 256, and the saturating narrowing keeps anything further out of
// range); byte pairs (p0, p1) come out of the windows by lookup and blend on 16-bit lanes.
template <class D16x>
HWY_INLINE bool mono8_blocks(D16x d16, const ImageView& src, hn::Vec<hn::Repartition<std::int32_t, D16x>> X0,
                             hn::Vec<hn::Repartition<std::int32_t, D16x>> Y0, hn::Vec<hn::Repartition<std::int32_t, D16x>> X1,
                             hn::Vec<hn::Repartition<std::int32_t, D16x>> Y1, std::uint8_t* out) {
  constexpr int kB = blocks_of<D16x>();
  const hn::Repartition<std::int32_t, D16x> d32;
  const hn::RebindToUnsigned<D16x> du16;
  const hn::Repartition<std::uint8_t, D16x> d8;
  using VU = hn::Vec<decltype(du16)>;
  int bx[kB], by[kB], ya_max = 0;
  const std::uint8_t* p[kB];
  for (int b = 0; b < kB; ++b) {
    const V32 x0 = block(d32, X0, b), y0 = block(d32, Y0, b), y1 = block(d32, Y1, b);
    const int xa = (hn::GetLane(x0) + 128) >> 16;  // the block's first left tap, as tap() rounds
    const int ya = (std::min(hn::GetLane(y0), hn::ExtractLane(y1, 3)) + 128) >> 16;
    if (xa < 0 || xa > src.width - 16 || ya < 0 || ya > src.height - 2) return false;
    bx[b] = 128 - xa * 65536, by[b] = 128 - ya * 65536, p[b] = src.row(ya) + xa, ya_max = std::max(ya_max, ya);
  }
  const auto ox = per_block(d32, bx), oy = per_block(d32, by);
  const VU rx = hn::BitCast(du16, narrow_blocks(d32, hn::ShiftRight<8>(hn::Add(X0, ox)), hn::ShiftRight<8>(hn::Add(X1, ox))));
  const VU ry = hn::BitCast(du16, narrow_blocks(d32, hn::ShiftRight<8>(hn::Add(Y0, oy)), hn::ShiftRight<8>(hn::Add(Y1, oy))));
  const auto fits = hn::And(hn::Lt(hn::BitCast(d16, rx), hn::Set(d16, 15 * 256)),
                            hn::Lt(hn::BitCast(d16, ry), hn::Set(d16, 2 * 256)));
  const auto ahead = hn::And(hn::Gt(hn::BitCast(d16, rx), hn::Set(d16, -1)), hn::Gt(hn::BitCast(d16, ry), hn::Set(d16, -1)));
  if (!hn::AllTrue(d16, hn::And(fits, ahead))) return false;
  const VU i = hn::ShiftRight<8>(rx), lower = hn::ShiftRight<8>(ry);
  const VU fx = hn::And(rx, hn::Set(du16, 0xFF)), fy = hn::And(ry, hn::Set(du16, 0xFF));
  const bool straddle = !hn::AllTrue(du16, hn::Eq(lower, hn::Zero(du16)));
  if (straddle && ya_max > src.height - 3) return false;
  const auto idx = hn::BitCast(d8, hn::Or(i, hn::ShiftLeft<8>(hn::Add(i, hn::Set(du16, 1)))));
  const auto r0 = load_windows(d8, p);
  for (auto& q : p) q += src.stride;
  const auto r1 = load_windows(d8, p);
  VU up = hn::BitCast(du16, hn::TableLookupBytes(r0, idx)), down = hn::BitCast(du16, hn::TableLookupBytes(r1, idx));
  if (straddle) {  // pixels one row lower take rows ya + 1, ya + 2
    for (auto& q : p) q += src.stride;
    const auto m = hn::Eq(lower, hn::Set(du16, 1));
    up = hn::IfThenElse(m, down, up);
    down = hn::IfThenElse(m, hn::BitCast(du16, hn::TableLookupBytes(load_windows(d8, p), idx)), down);
  }
  const VU v = lerp16(blend_pairs(up, fx), blend_pairs(down, fx), fy);
  const hn::Rebind<std::uint8_t, D16x> d8n;
  hn::StoreU(hn::DemoteTo(d8n, hn::BitCast(d16, v)), d8n, out);
  return true;
}

// Eight pixels: positions X0, Y0 for pixels 0-3, X1, Y1 for 4-7.
// room: as blend_store's, after the eighth pixel.
template <class T, int C>
HWY_INLINE void eight(const ImageView& src, V32 X0, V32 Y0, V32 X1, V32 Y1, std::uint8_t* out, bool room) {
  if constexpr (C == 1 && sizeof(T) == 1) {
    if (mono8_blocks(D16(), src, X0, Y0, X1, Y1, out)) return;
  } else if constexpr (C == 3) {
    std::uint8_t* o0[1] = {out};
    std::uint8_t* o1[1] = {out + 12};
    if (!rgb8_blocks(D8(), src, X0, Y0, o0)) four<T, C>(src, X0, Y0, out, true);
    if (!rgb8_blocks(D8(), src, X1, Y1, o1)) four<T, C>(src, X1, Y1, out + 12, room);
    return;
  }
  four<T, C>(src, X0, Y0, out, true);
  four<T, C>(src, X1, Y1, out + 4 * C * sizeof(T), room);
}

// One wide step; room: as blend_store's, after the step's last pixel.
template <class T, int C>
HWY_INLINE void wide(const ImageView& src, VW32 X0, VW32 Y0, VW32 X1, VW32 Y1, std::uint8_t* out, bool room) {
  if constexpr (C == 1 && sizeof(T) == 1) {
    if (mono8_blocks(DW16(), src, X0, Y0, X1, Y1, out)) return;
  } else if constexpr (C == 3) {  // pixels 8b..8b+3 from X0, 8b+4..8b+7 from X1
    std::uint8_t* o0[2] = {out, out + 24};
    std::uint8_t* o1[2] = {out + 12, out + 36};
    if (rgb8_blocks(DW8(), src, X0, Y0, o0) && rgb8_blocks(DW8(), src, X1, Y1, o1)) return;
  }
  const DW32 dw;
  for (int b = 0; b < kBlocks; ++b)
    eight<T, C>(src, block(dw, X0, b), block(dw, Y0, b), block(dw, X1, b), block(dw, Y1, b), out + 8 * b * C * sizeof(T),
                room || b + 1 < kBlocks);
}

// kStep positions from memory in the wide layout.
template <class D = DW32>
HWY_INLINE void load_wide(const std::int32_t* v, hn::Vec<D>& lo, hn::Vec<D>& hi) {
  const D d;
  if constexpr (kBlocks == 1) {
    lo = hn::LoadU(d, v), hi = hn::LoadU(d, v + 4);
  } else {
    const hn::Vec<D> a = hn::LoadU(d, v), b = hn::LoadU(d, v + 8);
    lo = hn::ConcatLowerLower(d, b, a), hi = hn::ConcatUpperUpper(d, b, a);
  }
}

// Positions from the row arrays (cells narrower than 16 px, cells the horizon crosses).
template <class T, int C>
void sample_row_simd(const ImageView& src, const std::int32_t* xs, const std::int32_t* ys, std::uint8_t* out, int n) {
  constexpr int kBytes = C * sizeof(T);
  const D32 d;
  int i = 0;
  for (; i + kStep <= n; i += kStep) {
    VW32 X0, X1, Y0, Y1;
    load_wide(xs + i, X0, X1), load_wide(ys + i, Y0, Y1);
    wide<T, C>(src, X0, Y0, X1, Y1, out + i * kBytes, i + kStep + 2 <= n);
  }
  for (; i + 8 <= n; i += 8)
    eight<T, C>(src, hn::LoadU(d, xs + i), hn::LoadU(d, ys + i), hn::LoadU(d, xs + i + 4), hn::LoadU(d, ys + i + 4),
                out + i * kBytes, i + 10 <= n);
  sample_row_scalar<T, C>(src, xs + i, ys + i, out + i * kBytes, n - i);
}

// Positions generated in registers along an affine cell segment, x_k = ax + k sx: the same
// integers as the scalar code's running sums (int32 arithmetic wraps alike).
template <class T, int C>
void sample_affine_simd(const ImageView& src, const Affine& a, std::uint8_t* out, int n) {
  constexpr int kBytes = C * sizeof(T);
  const DW32 dw;
  const VW32 lanes = hn::Iota(dw, 0), order = hn::Add(lanes, hn::And(lanes, hn::Set(dw, ~3)));  // the wide layout
  const VW32 sx = hn::Set(dw, a.sx), sy = hn::Set(dw, a.sy);
  VW32 X = hn::Add(hn::Set(dw, a.ax), hn::Mul(order, sx)), Y = hn::Add(hn::Set(dw, a.ay), hn::Mul(order, sy));
  const VW32 X4 = hn::Mul(hn::Set(dw, 4), sx), Y4 = hn::Mul(hn::Set(dw, 4), sy);
  const VW32 Xs = hn::Mul(hn::Set(dw, kStep), sx), Ys = hn::Mul(hn::Set(dw, kStep), sy);
  int i = 0;
  for (; i + kStep <= n; i += kStep, X = hn::Add(X, Xs), Y = hn::Add(Y, Ys))
    wide<T, C>(src, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + i * kBytes, i + kStep + 2 <= n);
  // The rest, fewer than kStep pixels, from pixel i on.
  alignas(64) std::int32_t xs[kStep], ys[kStep];
  const D32 d;
  const V32 l4 = hn::Iota(d, 0);
  // a + (i + k) s in wrapping 32-bit arithmetic, as the vectors and the scalar sums compute it.
  auto at = [&](std::int32_t a0, std::int32_t step, int k) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(a0) + static_cast<std::uint32_t>(i + k) * static_cast<std::uint32_t>(step));
  };
  for (int k = 0; k < kStep; k += 4) {
    hn::Store(hn::Add(hn::Set(d, at(a.ax, a.sx, k)), hn::Mul(l4, hn::Set(d, a.sx))), d, xs + k);
    hn::Store(hn::Add(hn::Set(d, at(a.ay, a.sy, k)), hn::Mul(l4, hn::Set(d, a.sy))), d, ys + k);
  }
  sample_row_simd<T, C>(src, xs, ys, out + i * kBytes, n - i);
}

template <class T, int C>
Samplers samplers_of() {
  return {sample_row_simd<T, C>, sample_affine_simd<T, C>};
}

Samplers simd_samplers(PixelFormat f) {
  switch (f) {
    case PixelFormat::Mono8: return samplers_of<std::uint8_t, 1>();
    case PixelFormat::Mono16: return samplers_of<std::uint16_t, 1>();
    case PixelFormat::Rgb8: return samplers_of<std::uint8_t, 3>();
  }
  return {};
}
#endif  // HWY_TARGET == HWY_SCALAR

// NOLINTNEXTLINE(google-readability-namespace-comments)
}  // namespace HWY_NAMESPACE
}  // namespace rsd::dsp::rectify_detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace rsd::dsp::rectify_detail {

HWY_EXPORT(simd_samplers);

Samplers dispatched_samplers(PixelFormat f) { return HWY_DYNAMIC_DISPATCH(simd_samplers)(f); }

std::vector<std::int64_t> simd_targets() {
  std::vector<std::int64_t> out;
  for (std::int64_t t = hwy::SupportedTargets() & HWY_TARGETS; t != 0; t &= t - 1) out.push_back(t & -t);
  return out;
}

void force_simd_target(std::int64_t target) { hwy::SetSupportedTargetsForTest(target); }

std::string simd_target_name() {
  const std::int64_t t = hwy::SupportedTargets() & HWY_TARGETS;
  return hwy::TargetName(t & -t);
}

std::string target_name(std::int64_t target) { return hwy::TargetName(target); }

}  // namespace rsd::dsp::rectify_detail
#endif  // HWY_ONCE
