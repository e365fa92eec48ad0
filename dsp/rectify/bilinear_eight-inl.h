// The bilinear sampler's SIMD kernels, part 3: RGB24 and U V pairs along affine segments that
// fit, eight samples per block. Included by bilinear_sampling_simd.cpp once per Highway target,
// after bilinear_blocks-inl.h (whose wide steps, Mono8 origins and blends it uses).
#if defined(RSD_DSP_RECTIFY_BILINEAR_EIGHT_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef RSD_DSP_RECTIFY_BILINEAR_EIGHT_INL_H_
#undef RSD_DSP_RECTIFY_BILINEAR_EIGHT_INL_H_
#else
#define RSD_DSP_RECTIFY_BILINEAR_EIGHT_INL_H_
#endif

#include <algorithm>
#include <cstdint>
#include <cstdlib>

#include "hwy/highway.h"
#include "dsp/rectify/bilinear_sampling.hpp"

HWY_BEFORE_NAMESPACE();
namespace rsd::dsp::rectify_detail {
namespace HWY_NAMESPACE {
#if HWY_TARGET != HWY_SCALAR
namespace hn = hwy::HWY_NAMESPACE;

// ---- RGB24 and U V pairs along affine segments, eight samples per block ----------------
//
// A block's eight samples of kBytes bytes are 8 kBytes output bytes: kBytes vectors of eight
// 16-bit lanes, each looked up in a 16-byte window of its own on the block's rows, from the
// left tap of its first sample. RGB24: A (bytes 0-7: pixels 0, 1 and the red and green of 2),
// B (bytes 8-15: the blue of 2, pixels 3, 4 and the red of 5), C (bytes 16-23: the green and
// blue of 5, pixels 6, 7), windows from pixels 0, 2 and 5; B's pixels 2-5 have left taps
// spanning up to floor(3 sx) + 1 px, so a window holds their taps while 3 sx < 4 (A's and C's
// three pixels while 2 sx < 3). U V pairs: samples 0-3 and 4-7, windows of eight pairs from
// samples 0 and 4 (3 sx < 6). Positions are relative to the block's origin as Mono8's
// (mono8_relative), so that the eight samples share one set of position lanes.

template <int kBytes>
constexpr int kWindows8 = kBytes;  // the vectors (and windows) of a block
template <int kBytes>
constexpr int kWindowFirst[3] = {0, kBytes == 3 ? 2 : 4, 5};  // each window's first sample
template <int kBytes>
constexpr int kMaxSpan8 = kBytes == 3 ? 4 : 6;  // 3 sx below this many px: every window fits

// The lookup patterns of window W, per lane: its sample k, component c (colour, or U / V).
struct Lanes8 {
  Pattern sample;  // (2k, 2k + 1): sample k's 16-bit lane
  Pattern origin;  // (2w + 1, 0x80): the high byte (tap column) of the window's first sample w
  Pattern colour;  // (c, c + kBytes): the left and right tap's byte from the sample's first
};
template <int kBytes>
constexpr Lanes8 lanes8(int window) {
  std::uint8_t sample[16]{}, origin[16]{}, colour[16]{};
  for (int lane = 0; lane < 8; ++lane) {
    const int byte = 8 * window + lane, k = byte / kBytes, c = byte % kBytes, w = kWindowFirst<kBytes>[window];
    const auto u8 = [](int v) { return static_cast<std::uint8_t>(v); };
    sample[2 * lane] = u8(2 * k), sample[2 * lane + 1] = u8(2 * k + 1);
    origin[2 * lane] = u8(2 * w + 1), origin[2 * lane + 1] = 0x80;
    colour[2 * lane] = u8(c), colour[2 * lane + 1] = u8(c + kBytes);
  }
  return {per_block(sample), per_block(origin), per_block(colour)};
}
template <int kBytes>
constexpr Lanes8 kLanes8[3] = {lanes8<kBytes>(0), lanes8<kBytes>(1), lanes8<kBytes>(2)};

// The lanes of window W blended: rx and ry hold each sample's position relative to the block's
// origin (mono8_relative: tap column i in the high byte, weight in the low), p[b] the block's
// window on its first row. Two lookups bring each lane its sample's rx and ry (the shuffles are
// the kernel's bottleneck: the rest is arithmetic); a lane's left tap is byte kBytes (i - i_w) + c
// of the window (i_w: the column of the window's first sample, 0 for window 0), its right tap
// kBytes bytes on.
template <int kBytes, int W, class DB, class VU>
HWY_INLINE VU window8(DB d8, const SamplePlane& src, const std::uint8_t* const* p, VU rx, VU ry, bool straddle) {
  const hn::DFromV<VU> du16;
  const Lanes8& l = kLanes8<kBytes>[W];
  const auto sample = load_pattern(d8, l.sample);
  const VU x = hn::BitCast(du16, hn::TableLookupBytes(hn::BitCast(d8, rx), sample));
  const VU y = hn::BitCast(du16, hn::TableLookupBytes(hn::BitCast(d8, ry), sample));
  const VU byte = hn::Set(du16, 0xFF);
  VU column = hn::ShiftRight<8>(x);
  if constexpr (W > 0) column = hn::Sub(column, hn::BitCast(du16, hn::TableLookupBytesOr0(hn::BitCast(d8, rx), load_pattern(d8, l.origin))));
  const auto idx = hn::BitCast(d8, hn::Add(hn::Mul(column, hn::Set(du16, kBytes * 0x0101)), hn::BitCast(du16, load_pattern(d8, l.colour))));
  const std::uint8_t* q[blocks_of<DB>()];
  for (int b = 0; b < blocks_of<DB>(); ++b) q[b] = p[b];
  VU up, down;
  tap_pairs(d8, src, q, idx, straddle, hn::ShiftRight<8>(y), up, down);
  const VU fx = hn::And(x, byte);
  return lerp16(blend_pairs(up, fx), blend_pairs(down, fx), hn::And(y, byte));
}

// Bytes 0-7 of each block: the low bytes of v's lanes, 8-15: w's (lanes below 256).
constexpr Pattern kLowThenHigh = per_block({0, 2, 4, 6, 8, 10, 12, 14, 1, 3, 5, 7, 9, 11, 13, 15});
template <class DB, class VU>
HWY_INLINE hn::Vec<DB> low_bytes(DB d8, VU v, VU w) {
  return hn::TableLookupBytes(hn::BitCast(d8, hn::Or(v, hn::ShiftLeft<8>(w))), load_pattern(d8, kLowThenHigh));
}

// Eight samples per block of segments known to fit (blocks8_fit), windows p[W][b]
// (block8_origins), positions X0 (samples 8b..8b+3), X1 (8b+4..8b+7): block b's 8 kBytes
// bytes to out + 8 kBytes b, 16-byte stores in order. room: 8 bytes after the last block may be
// written (RGB24's last store).
template <int kBytes, class D16x>
HWY_INLINE void affine_blocks8(D16x d16, const SamplePlane& src, const std::uint8_t* const (*p)[kBlocks], bool straddle,
                               hn::Vec<hn::Repartition<std::int32_t, D16x>> X0, hn::Vec<hn::Repartition<std::int32_t, D16x>> Y0,
                               hn::Vec<hn::Repartition<std::int32_t, D16x>> X1, hn::Vec<hn::Repartition<std::int32_t, D16x>> Y1,
                               std::uint8_t* out, bool room) {
  constexpr int kB = blocks_of<D16x>();
  const hn::RebindToUnsigned<D16x> du16;
  const hn::Repartition<std::uint8_t, D16x> d8;
  hn::Vec<decltype(du16)> rx, ry;
  mono8_relative(d16, X0, Y0, X1, Y1, rx, ry);
  const auto a = window8<kBytes, 0>(d8, src, p[0], rx, ry, straddle);
  const auto b = window8<kBytes, 1>(d8, src, p[1], rx, ry, straddle);
  const auto ab = low_bytes(d8, a, b);
  if constexpr (kBytes == 2) {
    hn::StoreU(ab, d8, out);  // block k's 16 bytes belong at out + 16 k: one store
  } else {
    const D8 w8;
    const auto c = window8<kBytes, 2>(d8, src, p[2], rx, ry, straddle);
    const auto cc = low_bytes(d8, c, c);
    const hn::Full64<std::uint8_t> w64;
    for (int k = 0; k < kB; ++k) {
      hn::StoreU(part<kB, D8>(d8, ab, k), w8, out + 24 * k);
      const auto c16 = part<kB, D8>(d8, cc, k);
      if (room || k + 1 < kB)
        hn::StoreU(c16, w8, out + 24 * k + 16);
      else
        hn::StoreU(hn::LowerHalf(w64, c16), w64, out + 24 * k + 16);
    }
  }
}

// Whether every block of eight samples among samples [0, n) of segment a fits its windows
// (affine_blocks8): 0 <= 3 sx < kMaxSpan8 px, the eight top taps within one row (8 |sy| < 1),
// the first left tap inside, the last window inside the row (it starts at or before the last
// left tap), and rows 3 before the bottom (a straddling block's third row).
template <int kBytes>
inline bool blocks8_fit(const SamplePlane& src, const Affine& a, int n) {
  if (n < 1 || a.sx < 0 || 3 * std::int64_t{a.sx} >= kMaxSpan8<kBytes> * 65536 || std::abs(std::int64_t{a.sy}) * 8 >= 65536)
    return false;
  const std::int64_t last = n - 1, x1 = a.ax + last * a.sx, y0 = a.ay, y1 = a.ay + last * a.sy;
  return ((a.ax + 128) >> 16) >= 0 && kBytes * ((x1 + 128) >> 16) + 16 <= kBytes * std::int64_t{src.width} &&
         ((std::min(y0, y1) + 128) >> 16) >= 0 && ((std::max(y0, y1) + 128) >> 16) <= src.height - 3;
}

// The windows of `count` blocks of eight samples of segment a from sample e0 on (blocks8_fit),
// to p[W][b0 + m]: on the block's rows (segment_origins), from the left tap of window W's first
// sample.
template <int kBytes>
HWY_INLINE void block8_origins(const SamplePlane& src, const Affine& a, int e0, int count, const std::uint8_t* (*p)[kBlocks],
                               int b0, bool& straddle) {
  int xa[kBlocks], ya[kBlocks];
  segment_origins(a, e0, count, xa, ya, straddle);
  std::int64_t x[kWindows8<kBytes>];  // the later windows' first samples, running sums
  for (int w = 1; w < kWindows8<kBytes>; ++w) x[w] = a.ax + std::int64_t{e0 + kWindowFirst<kBytes>[w]} * a.sx + 128;
  for (int m = 0; m < count; ++m) {
    const std::uint8_t* row = src.row(ya[m]);
    p[0][b0 + m] = row + kBytes * xa[m];
    for (int w = 1; w < kWindows8<kBytes>; ++w, x[w - 1] += 8 * std::int64_t{a.sx}) p[w][b0 + m] = row + kBytes * static_cast<int>(x[w] >> 16);
  }
}

#endif  // HWY_TARGET != HWY_SCALAR
// NOLINTNEXTLINE(google-readability-namespace-comments)
}  // namespace HWY_NAMESPACE
}  // namespace rsd::dsp::rectify_detail
HWY_AFTER_NAMESPACE();
#endif  // RSD_DSP_RECTIFY_BILINEAR_EIGHT_INL_H_
