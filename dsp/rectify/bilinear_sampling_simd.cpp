// The SIMD kernels of the bilinear sampler, one source for every instruction set: Google
// Highway compiles this file once per target (SSSE3, SSE4, AVX2, AVX-512, AVX-512 with VBMI
// and its portable EMU128 on x86-64; NEON, SVE and SVE2 on arm64) and picks the best the CPU
// runs at run time.
// Every kernel computes the integers of the scalar reference (bilinear_sampling.hpp) bit for
// bit; tests/dsp/rectify/test_bilinear_sampling.cpp compares each target with it.
//
// The taps are fetched by byte lookups inside 16-byte windows of the source rows, which every
// instruction set does per 128-bit block; so the kernels work in 128-bit blocks, as many per
// vector as a fixed-width target holds (AVX2 two, AVX-512 four: "wide steps"), one
// elsewhere (SSE, NEON, EMU128, and SVE whatever its vector length). Per block:
// - Mono8: 8 pixels through one window per row (two rows, three where the taps straddle a row
//   boundary), blended on 16-bit lanes (mono8_blocks); 8-bit samples two bytes apart (YUYV's
//   luma, 8-bit mosaic sites) alike, the window the even bytes of 32, merged into every other
//   output byte (mono8_blocks<true>);
// - RGB24: 4 pixels through one 5-pixel window per row, each output byte a 16-bit lane that
//   looks up its own colour's tap pair (four_blocks<kRgb24>);
// - U V pairs (NV12's chroma): 4 pixels through one 8-pair window per row, U and V in the two
//   16-bit halves of each pixel's lane (four_blocks<kPairs>); YUYV's U V alike from the even
//   bytes of 32, merged around the luma (four_blocks<kYuyvUV>);
// - along affine segments: Mono8 (and its strided kind) with the checks once per segment
//   (affine_fits); RGB24 and U V pairs, when the segment's ends show that every block fits
//   (blocks8_fit), 8 samples per block sharing one set of position lanes, their output bytes
//   in 16-bit lanes of three (RGB24) or two (U V) vectors, each vector through a window of its
//   own (affine_blocks8), else 4 per block with per-block checks in scalars (affine_blocks);
//   on AVX-512 with VBMI (Highway's AVX3_DL) these and Mono8 first try a wide step of 32
//   samples through one 128-byte window per row, looked up across two vectors (window128_step);
// - otherwise (Mono16, steps whose taps do not fit a window) 4 pixels on 32-bit lanes: windows
//   where the taps fit, else a gather of the 32-bit word at each left tap (it holds the right tap
//   too: bytes 0..1 for Mono8, both halves for Mono16 and U V; RGB24 gathers again at +3), only
//   when all four taps are at least 3 px inside the right edge so that the reads never leave the
//   row.
// Steps entirely outside the image store the plane's fill (0, or 128 for chroma); the rest (near
// the borders) go to the scalar pixel code. The parts live in bilinear_four-inl.h (32-bit lanes),
// bilinear_blocks-inl.h (wide steps, Mono8's blocks on 16-bit lanes), bilinear_four_blocks-inl.h
// (RGB24's and U V pairs' blocks of four on 16-bit lanes) and bilinear_eight-inl.h (blocks of
// eight along segments). Pixels are little-endian in memory.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "dsp/rectify/bilinear_sampling_simd.cpp"
#include "hwy/foreach_target.h"  // IWYU pragma: keep (before highway.h)
#include "hwy/highway.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "dsp/rectify/bilinear_sampling.hpp"

#include "dsp/rectify/bilinear_four-inl.h"
#include "dsp/rectify/bilinear_blocks-inl.h"
#include "dsp/rectify/bilinear_four_blocks-inl.h"
#include "dsp/rectify/bilinear_eight-inl.h"

HWY_BEFORE_NAMESPACE();
namespace rsd::dsp::rectify_detail {
namespace HWY_NAMESPACE {

// Highway's HWY_SCALAR target (an x86-64 CPU without SSSE3) has one-lane vectors only: there
// the kernels are the scalar reference itself.
#if HWY_TARGET == HWY_SCALAR
Samplers simd_samplers(SampleKind k) { return scalar_samplers(k); }
#else
namespace hn = hwy::HWY_NAMESPACE;

// The plane (T, C, kOut bytes a sample) four_blocks takes, as its FourKind, or -1.
template <class T, int C, int kOut>
constexpr int kFourKind = sizeof(T) != 1                ? -1
                          : C == 3 && kOut == 3         ? static_cast<int>(FourKind::kRgb24)
                          : C == 2 && kOut == 2         ? static_cast<int>(FourKind::kPairs)
                          : C == 2 && kOut == 4         ? static_cast<int>(FourKind::kYuyvUV)
                                                        : -1;
// Its stores merge 16 bytes that reach the next sample: only where the row goes on (room).
template <class T, int C, int kOut>
constexpr bool kMerged = kOut != C * static_cast<int>(sizeof(T));

// Four samples where the SIMD blocks do not fit: the 32-bit lanes (four), or for a strided
// plane the scalar code.
template <class T, int C, int kOut>
HWY_INLINE void four_fallback(const SamplePlane& src, V32 X, V32 Y, std::uint8_t* out, bool room) {
  if constexpr (kMerged<T, C, kOut>) {
    (void)room;
    alignas(16) std::int32_t xs[4], ys[4];
    hn::Store(X, D32(), xs), hn::Store(Y, D32(), ys);
    sample_row_strided<T>(src, xs, ys, out, 4);
  } else {
    four<T, C>(src, X, Y, out, room);
  }
}

// Eight pixels: positions X0, Y0 for pixels 0-3, X1, Y1 for 4-7; kOut bytes from one output
// pixel to the next (C sizeof(T), or more for a strided plane).
// room: as blend_store's, after the eighth pixel.
template <class T, int C, int kOut>
HWY_INLINE void eight(const SamplePlane& src, V32 X0, V32 Y0, V32 X1, V32 Y1, std::uint8_t* out, bool room) {
  constexpr bool kMerge = kMerged<T, C, kOut>;
  if constexpr (kFourKind<T, C, kOut> >= 0) {
    constexpr auto kKind = static_cast<FourKind>(kFourKind<T, C, kOut>);
    std::uint8_t* o0[1] = {out};
    std::uint8_t* o1[1] = {out + 4 * kOut};
    if (!four_blocks<kKind>(D8(), src, X0, Y0, o0)) four_fallback<T, C, kOut>(src, X0, Y0, out, true);
    if ((kMerge && !room) || !four_blocks<kKind>(D8(), src, X1, Y1, o1)) four_fallback<T, C, kOut>(src, X1, Y1, o1[0], room);
    return;
  } else if constexpr (C == 1 && sizeof(T) == 1) {  // Mono8, or samples two bytes apart
    if ((!kMerge || room) && mono8_blocks<kMerge>(D16(), src, X0, Y0, X1, Y1, out)) return;
  }
  four_fallback<T, C, kOut>(src, X0, Y0, out, true);
  four_fallback<T, C, kOut>(src, X1, Y1, out + 4 * kOut, room);
}

// Per block b of a wide step, the output of its pixels 8b (o0) and 8b + 4 (o1), whose positions
// X0 and X1 hold, for a plane of kOut bytes a pixel.
template <int kOut>
struct WideOutputs {
  std::uint8_t* o0[kBlocks];
  std::uint8_t* o1[kBlocks];
  explicit WideOutputs(std::uint8_t* out) {
    for (int b = 0; b < kBlocks; ++b) o0[b] = out + 8 * b * kOut, o1[b] = out + (8 * b + 4) * kOut;
  }
};

// One wide step; room: as blend_store's, after the step's last pixel.
template <class T, int C, int kOut>
HWY_INLINE void wide(const SamplePlane& src, VW32 X0, VW32 Y0, VW32 X1, VW32 Y1, std::uint8_t* out, bool room) {
  constexpr bool kMerge = kMerged<T, C, kOut>;
  if constexpr (kFourKind<T, C, kOut> >= 0) {
    constexpr auto kKind = static_cast<FourKind>(kFourKind<T, C, kOut>);
    const WideOutputs<kOut> o(out);
    if ((!kMerge || room) && four_blocks<kKind>(DW8(), src, X0, Y0, o.o0) && four_blocks<kKind>(DW8(), src, X1, Y1, o.o1))
      return;
  } else if constexpr (C == 1 && sizeof(T) == 1) {
    if ((!kMerge || room) && mono8_blocks<kMerge>(DW16(), src, X0, Y0, X1, Y1, out)) return;
  }
  const DW32 dw;
  for (int b = 0; b < kBlocks; ++b)
    eight<T, C, kOut>(src, block(dw, X0, b), block(dw, Y0, b), block(dw, X1, b), block(dw, Y1, b), out + 8 * b * kOut,
                      room || b + 1 < kBlocks);
}

// kStep positions from memory in the wide layout (block b of lo: 8b..8b+3, of hi: 8b+4..8b+7).
template <class D = DW32>
HWY_INLINE void load_wide(const std::int32_t* v, hn::Vec<D>& lo, hn::Vec<D>& hi) {
  const D d;
  if constexpr (blocks_of<D>() == 1) {
    lo = hn::LoadU(d, v), hi = hn::LoadU(d, v + 4);
  } else if constexpr (blocks_of<D>() == 2) {
    const hn::Vec<D> a = hn::LoadU(d, v), b = hn::LoadU(d, v + 8);
    lo = hn::ConcatLowerLower(d, b, a), hi = hn::ConcatUpperUpper(d, b, a);
  } else {
    const hn::Half<D> dh;
    hn::Vec<decltype(dh)> lo0, hi0, lo1, hi1;
    load_wide<decltype(dh)>(v, lo0, hi0), load_wide<decltype(dh)>(v + 4 * blocks_of<D>(), lo1, hi1);
    lo = hn::Combine(d, lo1, lo0), hi = hn::Combine(d, hi1, hi0);
  }
}

// The scalar reference for the last few pixels of a row.
template <class T, int C, int kOut>
void scalar_rest(const SamplePlane& src, const std::int32_t* xs, const std::int32_t* ys, std::uint8_t* out, int n) {
  if constexpr (kOut != C * sizeof(T))
    sample_row_strided<T>(src, xs, ys, out, n);
  else
    sample_row_scalar<T, C>(src, xs, ys, out, n);
}

// Positions from the row arrays (cells narrower than 16 px, cells the horizon crosses).
template <class T, int C, int kOut>
void sample_row_simd(const SamplePlane& src, const std::int32_t* xs, const std::int32_t* ys, std::uint8_t* out, int n) {
  constexpr int kBytes = kOut;
  const D32 d;
  int i = 0;
  for (; i + kStep <= n; i += kStep) {
    VW32 X0, X1, Y0, Y1;
    load_wide(xs + i, X0, X1), load_wide(ys + i, Y0, Y1);
    wide<T, C, kOut>(src, X0, Y0, X1, Y1, out + i * kBytes, i + kStep + 2 <= n);
  }
  for (; i + 8 <= n; i += 8)
    eight<T, C, kOut>(src, hn::LoadU(d, xs + i), hn::LoadU(d, ys + i), hn::LoadU(d, xs + i + 4), hn::LoadU(d, ys + i + 4),
                out + i * kBytes, i + 10 <= n);
  scalar_rest<T, C, kOut>(src, xs + i, ys + i, out + i * kBytes, n - i);
}

// The kinds whose affine segments go through affine_blocks (bilinear_four_blocks-inl.h).
template <class T, int C, int kOut>
constexpr bool kAffineBlocks = sizeof(T) == 1 && (C == 3 || C == 2) && kOut == C;

// affine_blocks' dummy window needs 16 bytes in a row and three rows.
template <int C>
HWY_INLINE bool affine_blocks_fit(const SamplePlane& src) {
  return C * src.width >= 16 && src.height >= 3;
}

// One wide step of affine blocks: pixels 8b..8b+3 of block b at X0 (segments s0), 8b+4..8b+7 at X1.
template <class T, int C>
HWY_INLINE void affine_step(const SamplePlane& src, const BlockSegment* s0, const BlockSegment* s1, VW32 X0, VW32 Y0, VW32 X1,
                            VW32 Y1, std::uint8_t* out) {
  const WideOutputs<C> o(out);
  affine_blocks<T, C>(DW8(), src, s0, X0, Y0, o.o0);
  affine_blocks<T, C>(DW8(), src, s1, X1, Y1, o.o1);
}

// Whether the blocks of eight over samples [0, n) of segment a (whole blocks) fit (blocks8_fit).
template <class T, int C>
HWY_INLINE bool blocks_fit(const SamplePlane& src, const Affine& a, int n) {
  return blocks8_fit<C * sizeof(T)>(src, a, n);
}

// One wide step of samples known to fit (blocks_fit), whose blocks come from segment lo from
// sample e_lo on (blocks below `split`) and from hi from e_hi on (the others): the same segment
// for a step along one cell, two for two cells of half a step. room: as sample_affine_simd's
// room_after, after the step.
template <class T, int C>
HWY_INLINE void fitted_step(const SamplePlane& src, const Affine& lo, int e_lo, const Affine& hi, int e_hi, int split, VW32 X0,
                            VW32 Y0, VW32 X1, VW32 Y1, std::uint8_t* out, bool room) {
  constexpr int kBytes = C * sizeof(T);
  const std::uint8_t* p[kWindows8<kBytes>][kBlocks];
  bool straddle = false;
  block8_origins<kBytes>(src, lo, e_lo, split, p, 0, straddle);
  if (split < kBlocks) block8_origins<kBytes>(src, hi, e_hi, kBlocks - split, p, split, straddle);
  affine_blocks8<kBytes>(DW16(), src, p, straddle, X0, Y0, X1, Y1, out, room);
}

// Positions of samples [c0, c0 + n) of a run of cells into xs, ys (n rounded up to 4): a + e s
// for sample e of its cell, in wrapping 32-bit arithmetic like the scalar running sums. Groups
// of four never straddle two cells: cell_n and c0 are multiples of 4, or there is one cell.
HWY_INLINE void cell_positions(const Affine* a, int cell_n, int c0, int n, std::int32_t* xs, std::int32_t* ys) {
  const D32 d;
  const V32 l4 = hn::Iota(d, 0);
  auto at = [](std::int32_t a0, std::int32_t step, int e) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(a0) + static_cast<std::uint32_t>(e) * static_cast<std::uint32_t>(step));
  };
  for (int k = 0; k < n; k += 4) {
    const int c = (c0 + k) / cell_n, e = c0 + k - c * cell_n;
    hn::Store(hn::Add(hn::Set(d, at(a[c].ax, a[c].sx, e)), hn::Mul(l4, hn::Set(d, a[c].sx))), d, xs + k);
    hn::Store(hn::Add(hn::Set(d, at(a[c].ay, a[c].sy, e)), hn::Mul(l4, hn::Set(d, a[c].sy))), d, ys + k);
  }
}

// Positions generated in registers along an affine cell segment, x_k = ax + k sx: the same
// integers as the scalar code's running sums (int32 arithmetic wraps alike).
// room_after: the row goes on at least three samples after the segment (in the same run), so
// that a store may write 8 bytes past it.
template <class T, int C, int kOut>
HWY_INLINE void sample_affine_simd(const SamplePlane& src, const Affine& a, std::uint8_t* out, int n, bool room_after) {
  constexpr int kBytes = kOut;
  const DW32 dw;
  const VW32 lanes = hn::Iota(dw, 0), order = hn::Add(lanes, hn::And(lanes, hn::Set(dw, ~3)));  // the wide layout
  const VW32 sx = hn::Set(dw, a.sx), sy = hn::Set(dw, a.sy);
  VW32 X = hn::Add(hn::Set(dw, a.ax), hn::Mul(order, sx)), Y = hn::Add(hn::Set(dw, a.ay), hn::Mul(order, sy));
  const VW32 X4 = hn::ShiftLeft<2>(sx), Y4 = hn::ShiftLeft<2>(sy);  // 4 s and kStep s, wrapping like products
  const VW32 Xs = hn::ShiftLeft<kStepShift>(sx), Ys = hn::ShiftLeft<kStepShift>(sy);
  int i = 0;
  if constexpr (C == 1 && sizeof(T) == 1) {  // Mono8 and 8-bit samples two bytes apart: most segments need no checks
    constexpr bool kEven = kOut == 2;
    // The merged 16 bytes of a strided block reach the next sample's pair: the last step needs room.
    const int end = kEven && !room_after ? n - 1 : n;
    if constexpr (kWindow128 && !kEven) {  // with VBMI: one window per step, while they fit
      if (window128_slopes<1>(a))
        for (; i + kStep <= n; i += kStep, X = hn::Add(X, Xs), Y = hn::Add(Y, Ys))
          if (!window128_step<1>(src, a, i, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + i)) break;
    }
    if (i + kStep <= end && affine_fits<kEven>(src, a, end / kStep * kStep))
      for (; i + kStep <= end; i += kStep, X = hn::Add(X, Xs), Y = hn::Add(Y, Ys)) {
        int xa[kBlocks], ya[kBlocks];
        bool straddle = false;
        segment_origins(a, i, kBlocks, xa, ya, straddle);
        mono8_affine_blocks<kEven>(DW16(), src, xa, ya, straddle, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + i * kOut);
      }
  } else if constexpr (kAffineBlocks<T, C, kOut>) {  // RGB24, U V pairs: checks per segment, else per block
    if constexpr (kWindow128) {  // with VBMI: one window per step, while they fit
      if (window128_slopes<kBytes>(a))
        for (; i + kStep <= n; i += kStep, X = hn::Add(X, Xs), Y = hn::Add(Y, Ys))
          if (!window128_step<kBytes>(src, a, i, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + i * kBytes)) break;
    }
    if (i + kStep > n) {  // every whole step taken above
    } else if (blocks_fit<T, C>(src, a, n / kStep * kStep)) {
      for (; i + kStep <= n; i += kStep, X = hn::Add(X, Xs), Y = hn::Add(Y, Ys))
        fitted_step<T, C>(src, a, i, a, i, kBlocks, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + i * kBytes,
                          room_after || i + kStep + 3 <= n);
    } else if (affine_blocks_fit<C>(src)) {
      for (; i + kStep <= n; i += kStep, X = hn::Add(X, Xs), Y = hn::Add(Y, Ys)) {
        BlockSegment s0[kBlocks], s1[kBlocks];
        for (int b = 0; b < kBlocks; ++b) s0[b] = {&a, i + 8 * b}, s1[b] = {&a, i + 8 * b + 4};
        affine_step<T, C>(src, s0, s1, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + i * kBytes);
      }
    }
  }
  for (; i + kStep <= n; i += kStep, X = hn::Add(X, Xs), Y = hn::Add(Y, Ys))
    wide<T, C, kOut>(src, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + i * kBytes, room_after || i + kStep + 2 <= n);
  if (i == n) return;  // (cells are whole steps, as a rule)
  // The rest, fewer than kStep pixels, from pixel i on: the segment as a run of one cell.
  alignas(64) std::int32_t xs[kStep], ys[kStep];
  cell_positions(&a, n, i, n - i, xs, ys);
  sample_row_simd<T, C, kOut>(src, xs, ys, out + i * kBytes, n - i);
}

// The positions of a wide step of two cells of half a step, lo in the lower blocks and hi in the
// upper ones, in the wide layout (X: pixels 8b..8b+3 of each block, X + X4: 8b+4..8b+7).
HWY_INLINE void paired_positions(const Affine& lo, const Affine& hi, VW32& X, VW32& Y, VW32& X4, VW32& Y4) {
  const DW32 dw;
  const hn::Half<DW32> dh;
  const auto lanes = hn::Iota(dh, 0), order = hn::Add(lanes, hn::And(lanes, hn::Set(dh, ~3)));  // the wide layout
  auto half = [&](std::int32_t a0, std::int32_t s) { return hn::Add(hn::Set(dh, a0), hn::Mul(order, hn::Set(dh, s))); };
  X = hn::Combine(dw, half(hi.ax, hi.sx), half(lo.ax, lo.sx));
  Y = hn::Combine(dw, half(hi.ay, hi.sy), half(lo.ay, lo.sy));
  X4 = hn::ShiftLeft<2>(hn::Combine(dw, hn::Set(dh, hi.sx), hn::Set(dh, lo.sx)));  // 4 s, wrapping
  Y4 = hn::ShiftLeft<2>(hn::Combine(dw, hn::Set(dh, hi.sy), hn::Set(dh, lo.sy)));
}

// RGB24 or U V pairs in cells of half a wide step (16-sample chroma cells on AVX-512): two per
// step, the lower blocks from the first, the upper from the second; a last odd or short cell
// alone.
template <class T, int C, int kOut>
HWY_INLINE void paired_cells(const SamplePlane& src, const Affine* a, int total, std::uint8_t* out) {
  constexpr int kHalf = kStep / 2, kHalfBlocks = kBlocks / 2;
  int c0 = 0, k = 0;
  for (; c0 + kStep <= total; c0 += kStep, k += 2) {
    const Affine &lo = a[k], &hi = a[k + 1];
    VW32 X, Y, X4, Y4;
    paired_positions(lo, hi, X, Y, X4, Y4);
    if (blocks_fit<T, C>(src, lo, kHalf) && blocks_fit<T, C>(src, hi, kHalf)) {
      fitted_step<T, C>(src, lo, 0, hi, 0, kHalfBlocks, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + c0 * kOut,
                        c0 + kStep + 3 <= total);
      continue;
    }
    BlockSegment s0[kBlocks], s1[kBlocks];
    for (int b = 0; b < kBlocks; ++b) {
      const Affine* cell = b < kHalfBlocks ? &lo : &hi;
      const int e = 8 * (b % std::max(kHalfBlocks, 1));  // (no blocks at all on the narrowest targets)
      s0[b] = {cell, e}, s1[b] = {cell, e + 4};
    }
    affine_step<T, C>(src, s0, s1, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + c0 * kOut);
  }
  for (; c0 < total; c0 += kHalf, ++k)
    sample_affine_simd<T, C, kOut>(src, a[k], out + c0 * kOut, std::min(kHalf, total - c0), c0 + kHalf + 3 <= total);
}

// Mono8 (and 8-bit samples two bytes apart) in cells of half a wide step (16-px cells on
// AVX-512, 16-sample mosaic sites of 32-px cells): two cells a step, each checked to fit
// (affine_fits); a step that does not, and a merged step at the end of the run (no room after
// it), through positions, as is the rest.
template <class T, int C, int kOut>
HWY_INLINE void paired_mono8_cells(const SamplePlane& src, const Affine* a, int total, std::uint8_t* out) {
  constexpr int kHalf = kStep / 2, kHalfBlocks = kBlocks / 2;
  constexpr bool kEven = kOut == 2;
  alignas(64) std::int32_t xs[kStep], ys[kStep];
  int c0 = 0, k = 0;
  for (; c0 + kStep <= total; c0 += kStep, k += 2) {
    const Affine &lo = a[k], &hi = a[k + 1];
    if (!(kEven && c0 + kStep == total) && affine_fits<kEven>(src, lo, kHalf) && affine_fits<kEven>(src, hi, kHalf)) {
      VW32 X, Y, X4, Y4;
      paired_positions(lo, hi, X, Y, X4, Y4);
      int xa[kBlocks], ya[kBlocks];
      bool straddle = false;
      segment_origins(lo, 0, kHalfBlocks, xa, ya, straddle);
      segment_origins(hi, 0, kHalfBlocks, xa + kHalfBlocks, ya + kHalfBlocks, straddle);
      mono8_affine_blocks<kEven>(DW16(), src, xa, ya, straddle, X, Y, hn::Add(X, X4), hn::Add(Y, Y4), out + c0 * kOut);
      continue;
    }
    cell_positions(a, kHalf, c0, kStep, xs, ys);
    sample_row_simd<T, C, kOut>(src, xs, ys, out + c0 * kOut, kStep);
  }
  if (c0 < total) {
    cell_positions(a, kHalf, c0, total - c0, xs, ys);
    sample_row_simd<T, C, kOut>(src, xs, ys, out + c0 * kOut, total - c0);
  }
}

// A run of cells in one call: the constants of the segment code stay in registers. Cells
// narrower than a wide step (16-sample chroma cells, 16-px cells on AVX-512) would each end in
// the short tail: their positions go through arrays instead, a chunk of cells at a time, so
// that the kernels still take whole wide steps.
template <class T, int C, int kOut>
void sample_cells_simd(const SamplePlane& src, const Affine* a, int cell_n, int total, std::uint8_t* out) {
  if (cell_n >= kStep || cell_n % 8 != 0) {
    for (int c0 = 0, k = 0; c0 < total; c0 += cell_n, ++k)  // as for_each_cell, with the segment inlined
      sample_affine_simd<T, C, kOut>(src, a[k], out + c0 * kOut, std::min(cell_n, total - c0), c0 + cell_n + 3 <= total);
    return;
  }
  if constexpr (kAffineBlocks<T, C, kOut> && kBlocks >= 2) {
    if (2 * cell_n == kStep && affine_blocks_fit<C>(src)) return paired_cells<T, C, kOut>(src, a, total, out);
  }
  if constexpr (C == 1 && sizeof(T) == 1 && kBlocks >= 2) {
    if (2 * cell_n == kStep) return paired_mono8_cells<T, C, kOut>(src, a, total, out);
  }
  constexpr int kChunk = 256;
  alignas(64) std::int32_t xs[kChunk + 4], ys[kChunk + 4];
  for (int c0 = 0; c0 < total; c0 += kChunk) {
    const int n = std::min(kChunk, total - c0);
    cell_positions(a, cell_n, c0, n, xs, ys);
    sample_row_simd<T, C, kOut>(src, xs, ys, out + c0 * kOut, n);
  }
}

template <class T, int C, int kOut = C * sizeof(T)>
Samplers samplers_of() {
  return {sample_row_simd<T, C, kOut>, sample_cells_simd<T, C, kOut>};
}

Samplers simd_samplers(SampleKind k) {
  switch (k) {
    case SampleKind::U8: return samplers_of<std::uint8_t, 1>();
    case SampleKind::U8x2: return samplers_of<std::uint8_t, 2>();
    case SampleKind::U8x3: return samplers_of<std::uint8_t, 3>();
    case SampleKind::U16: return samplers_of<std::uint16_t, 1>();
    case SampleKind::StridedU8x2: return samplers_of<std::uint8_t, 1, 2>();
    case SampleKind::StridedUV4: return samplers_of<std::uint8_t, 2, 4>();
    case SampleKind::StridedU8:
    case SampleKind::StridedU16: break;
  }
  return scalar_samplers(k);
}
#endif  // HWY_TARGET == HWY_SCALAR

// NOLINTNEXTLINE(google-readability-namespace-comments)
}  // namespace HWY_NAMESPACE
}  // namespace rsd::dsp::rectify_detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace rsd::dsp::rectify_detail {

HWY_EXPORT(simd_samplers);

Samplers dispatched_samplers(SampleKind k) { return HWY_DYNAMIC_DISPATCH(simd_samplers)(k); }

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
