// The bilinear sampler's SIMD kernels, part 4: RGB24 and U V pairs along affine segments that
// fit, eight samples per block; and on AVX-512 with VBMI, Mono8, RGB24 and U V pairs a wide step
// per window.
// Included by bilinear_sampling_simd.cpp once per Highway target, after bilinear_blocks-inl.h
// (whose wide steps, Mono8 origins and blends it uses).
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
  // 3 sx < kMaxSpan8 px; the last window's 16 bytes end in the row: kBytes x + 16 <= kBytes width.
  return segment_within(a, n, (kMaxSpan8<kBytes> * 65536 + 2) / 3, src.width - (16 + kBytes - 1) / kBytes, src.height - 3);
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

#if HWY_TARGET == HWY_AVX3_DL
// ---- Mono8, RGB24 and U V pairs along affine segments, a wide step per 128-byte window (VBMI) ----
//
// AVX-512 VBMI looks bytes up across two whole vectors (vpermi2b: a 128-byte table), so a wide
// step's 32 samples need no per-block windows: one window of 128 bytes per row from the step's
// first left tap (128 Mono8 pixels, 42 RGB24 pixels, 64 U V pairs; two 64-byte loads a row) and
// one origin per step instead of one per block. A lane per output byte, as the blocks have
// them: Mono8's 32 lanes are the step's pixels in order; U V pairs split each
// sample's 32-bit lane into its U and V lanes (pairs_blend); RGB24's three vectors of 32 lanes
// take their pixels' positions by a 16-bit lookup (vpermw) from the step's 32 positions, which
// the wide layout narrowed block by block puts in pixel order. A step fits while its last left
// tap lies at most N - 2 samples right of its first (31 sx <= N - 2 px, N = 128 / kBytes), its
// top taps span at most one row boundary (31 |sy| < 1 row) and lie above the last row, and its
// window ends in the row; a segment's steps go this way until one does not fit.
constexpr bool kWindow128 = true;

// The byte of the 128 in lo, hi that each byte of idx names (bits 0-6).
HWY_INLINE hn::Vec<DW8> lookup128(hn::Vec<DW8> lo, hn::Vec<DW8> hi, hn::Vec<DW8> idx) {
  return hn::Vec<DW8>{_mm512_permutex2var_epi8(lo.raw, idx.raw, hi.raw)};
}

template <int kBytes>
constexpr int kWindowSamples = 128 / kBytes;

// The slopes a window of 128 bytes per step takes (the rest is checked per step).
template <int kBytes>
inline bool window128_slopes(const Affine& a) {
  constexpr std::uint32_t kMaxSx = (kWindowSamples<kBytes> - 2) * 65536u / 31;
  return static_cast<std::uint32_t>(a.sx) <= kMaxSx && std::abs(std::int64_t{a.sy}) * 31 < 65536;
}

// A step's window: the rows (two, three when its top taps straddle a row boundary) from its
// origin (xa, ya) in samples.
struct Step128 {
  struct Row {
    hn::Vec<DW8> lo, hi;
  } rows[3];
  bool straddle;
  int xa, ya;
};

// The window of samples [e, e + 32) of segment a (window128_slopes); false when its top taps
// leave the rows [0, height - 2] (the rows below them must exist) or its 128 bytes would leave
// the row. Checked per step: a chroma cell is one step, and a check per segment cost as much as
// the step's own scalars.
template <int kBytes>
HWY_INLINE bool step128(const SamplePlane& src, const Affine& a, int e, Step128& s) {
  const std::int64_t x = a.ax + std::int64_t{e} * a.sx + 128, y = a.ay + std::int64_t{e} * a.sy + 128;
  const std::int64_t y31 = y + 31 * std::int64_t{a.sy}, top = std::min(y, y31), bottom = std::max(y, y31);
  const auto below = [](std::int64_t v, int n) {  // 0 <= v >> 16 < n
    return static_cast<std::uint64_t>(v) < static_cast<std::uint64_t>(std::max(n, 0)) << 16;
  };
  constexpr int kRoom = (128 + kBytes - 1) / kBytes;  // kBytes xa + 128 <= kBytes width
  if (!(below(x, src.width - kRoom + 1) & below(top, src.height - 1) & below(bottom, src.height - 1))) return false;
  s.xa = static_cast<int>(x >> 16), s.ya = static_cast<int>(top >> 16), s.straddle = (bottom >> 16) != s.ya;
  const DW8 d8;
  const std::uint8_t* p = src.row(s.ya) + kBytes * s.xa;
  for (int r = 0; r < (s.straddle ? 3 : 2); ++r, p += src.stride) s.rows[r] = {hn::LoadU(d8, p), hn::LoadU(d8, p + 64)};
  return true;
}

// One vector of 32 lanes blended: idx their tap pairs' bytes in the window, x16 and y16 their
// positions relative to it (1/256 px: the weights in the low bytes, y16's high byte the row).
HWY_INLINE hn::Vec<DWU16> blend128(const Step128& s, hn::Vec<DW8> idx, hn::Vec<DWU16> x16, hn::Vec<DWU16> y16) {
  const DWU16 du16;
  auto pick = [&](const Step128::Row& r) { return hn::BitCast(du16, lookup128(r.lo, r.hi, idx)); };
  auto up = pick(s.rows[0]), down = pick(s.rows[1]);
  if (s.straddle) {
    const auto m = hn::Eq(hn::ShiftRight<8>(y16), hn::Set(du16, 1));
    up = hn::IfThenElse(m, down, up);
    down = hn::IfThenElse(m, pick(s.rows[2]), down);
  }
  const auto byte = hn::Set(du16, 0xFF);
  return lerp16(blend_pairs(up, hn::And(x16, byte)), blend_pairs(down, hn::And(x16, byte)), hn::And(y16, byte));
}

// Positions X (in the wide layout) relative to the step's origin, in 1/256 px.
HWY_INLINE VW32 relative128(VW32 X, int origin) {
  const DW32 d32;
  return hn::Sub(hn::ShiftRight<8>(hn::Add(X, hn::Set(d32, 128))), hn::Set(d32, origin * 256));
}

// The step's 32 positions relative to its origin, narrowed to 16-bit lanes in pixel order (the
// wide layout narrowed block by block); below 128 px, so nothing saturates. Mono8 and RGB24.
HWY_INLINE void pixel_order128(const Step128& s, VW32 X0, VW32 Y0, VW32 X1, VW32 Y1, hn::Vec<DWU16>& x16, hn::Vec<DWU16>& y16) {
  const DWU16 du16;
  const DW32 d32;
  x16 = hn::BitCast(du16, narrow_blocks(d32, relative128(X0, s.xa), relative128(X1, s.xa)));
  y16 = hn::BitCast(du16, narrow_blocks(d32, relative128(Y0, s.ya), relative128(Y1, s.ya)));
}

// The low bytes of 32 lanes to out (32 bytes).
HWY_INLINE void store_low_bytes32(hn::Vec<DWU16> v, std::uint8_t* out) {
  const hn::Rebind<std::uint8_t, DWU16> d8n;
  hn::StoreU(hn::DemoteTo(d8n, hn::BitCast(hn::RebindToSigned<DWU16>(), v)), d8n, out);
}

// U V pairs: output byte 2s + c (sample s, U or V) from the lanes: sample s sits in lane s % 4
// of block s / 8 of X0 (s % 8 < 4) or X1, its U in the low byte of the lane's low half, V of
// the high.
constexpr Pattern pairs_order128() {
  Pattern r;
  for (int s = 0; s < 32; ++s)
    for (int c = 0; c < 2; ++c)
      r.b[2 * s + c] = static_cast<std::uint8_t>((s % 8 < 4 ? 0 : 64) + 16 * (s / 8) + 4 * (s % 4) + 2 * c);
  return r;
}
constexpr Pattern kPairsOrder128 = pairs_order128();

HWY_INLINE void pairs_step128(const Step128& s, VW32 X0, VW32 Y0, VW32 X1, VW32 Y1, std::uint8_t* out) {
  const DWU16 du16;
  const DW8 d8;
  const DW32 d32;
  auto lanes = [&](VW32 X, VW32 Y) {
    const auto rx = relative128(X, s.xa), ry = relative128(Y, s.ya);
    const auto x16 = hn::BitCast(du16, hn::Or(rx, hn::ShiftLeft<16>(rx))), y16 = hn::BitCast(du16, hn::Or(ry, hn::ShiftLeft<16>(ry)));
    const auto i2 = hn::ShiftLeft<1>(hn::ShiftRight<8>(x16));  // the left tap's U byte, V one on
    const auto idx = hn::BitCast(d8, hn::Add(hn::Or(i2, hn::ShiftLeft<8>(i2)), hn::BitCast(du16, hn::Set(d32, 0x03010200))));
    return hn::BitCast(d8, blend128(s, idx, x16, y16));
  };
  hn::StoreU(lookup128(lanes(X0, Y0), lanes(X1, Y1), load_pattern(d8, kPairsOrder128)), d8, out);
}

// RGB24: lane j of vector v is output byte 32 v + j, the colour c = (32 v + j) % 3 of pixel
// (32 v + j) / 3: its pixel (a 16-bit lookup) and the bytes c and c + 3 of its pixel's taps.
struct alignas(64) Pixels16 {
  std::uint16_t w[32] = {};
};
constexpr Pixels16 rgb_pixels128(int v) {
  Pixels16 r;
  for (int j = 0; j < 32; ++j) r.w[j] = static_cast<std::uint16_t>((32 * v + j) / 3);
  return r;
}
constexpr Pattern rgb_colours128(int v) {
  Pattern r;
  for (int j = 0; j < 32; ++j) {
    const int c = (32 * v + j) % 3;
    r.b[2 * j] = static_cast<std::uint8_t>(c), r.b[2 * j + 1] = static_cast<std::uint8_t>(c + 3);
  }
  return r;
}
constexpr Pixels16 kRgbPixels128[3] = {rgb_pixels128(0), rgb_pixels128(1), rgb_pixels128(2)};
constexpr Pattern kRgbColours128[3] = {rgb_colours128(0), rgb_colours128(1), rgb_colours128(2)};
// Bytes 0-63 of a step: the low bytes of vectors 0 and 1.
constexpr Pattern even_bytes128() {
  Pattern r;
  for (int j = 0; j < 64; ++j) r.b[j] = static_cast<std::uint8_t>(2 * j);
  return r;
}
constexpr Pattern kEvenBytes128 = even_bytes128();

HWY_INLINE void rgb_step128(const Step128& s, VW32 X0, VW32 Y0, VW32 X1, VW32 Y1, std::uint8_t* out) {
  const DWU16 du16;
  const DW8 d8;
  hn::Vec<DWU16> x16, y16;
  pixel_order128(s, X0, Y0, X1, Y1, x16, y16);
  auto vector = [&](int v) {
    const auto pixel = hn::Load(du16, kRgbPixels128[v].w);
    const auto px = hn::Vec<DWU16>{_mm512_permutexvar_epi16(pixel.raw, x16.raw)};
    const auto py = hn::Vec<DWU16>{_mm512_permutexvar_epi16(pixel.raw, y16.raw)};
    const auto col = hn::ShiftRight<8>(px);  // the left tap's pixel: bytes 3 col + c and + 3
    const auto idx = hn::BitCast(d8, hn::Add(hn::Mul(col, hn::Set(du16, 0x0303)), hn::BitCast(du16, load_pattern(d8, kRgbColours128[v]))));
    return blend128(s, idx, px, py);
  };
  hn::StoreU(lookup128(hn::BitCast(d8, vector(0)), hn::BitCast(d8, vector(1)), load_pattern(d8, kEvenBytes128)), d8, out);
  store_low_bytes32(vector(2), out + 64);
}

// Mono8: the 32 lanes are the step's pixels, in order; each looks up its two taps (bytes col,
// col + 1 of the window).
HWY_INLINE void mono8_step128(const Step128& s, VW32 X0, VW32 Y0, VW32 X1, VW32 Y1, std::uint8_t* out) {
  const DWU16 du16;
  const DW8 d8;
  hn::Vec<DWU16> x16, y16;
  pixel_order128(s, X0, Y0, X1, Y1, x16, y16);
  const auto idx = hn::BitCast(d8, hn::Add(hn::Mul(hn::ShiftRight<8>(x16), hn::Set(du16, 0x0101)), hn::Set(du16, 0x0100)));
  store_low_bytes32(blend128(s, idx, x16, y16), out);
}

// A wide step of samples [e, e + 32) of segment a (window128_slopes), positions X0 .. Y1 in the
// wide layout, to out (32 kBytes bytes); false (nothing written) when it does not fit (step128).
template <int kBytes>
HWY_INLINE bool window128_step(const SamplePlane& src, const Affine& a, int e, VW32 X0, VW32 Y0, VW32 X1, VW32 Y1,
                               std::uint8_t* out) {
  Step128 s;
  if (!step128<kBytes>(src, a, e, s)) return false;
  if constexpr (kBytes == 1)
    mono8_step128(s, X0, Y0, X1, Y1, out);
  else if constexpr (kBytes == 2)
    pairs_step128(s, X0, Y0, X1, Y1, out);
  else
    rgb_step128(s, X0, Y0, X1, Y1, out);
  return true;
}
#else
constexpr bool kWindow128 = false;
// Declared for the callers' discarded `if constexpr (kWindow128)` branches; never defined.
template <int kBytes>
bool window128_slopes(const Affine& a);
template <int kBytes>
bool window128_step(const SamplePlane& src, const Affine& a, int e, VW32 X0, VW32 Y0, VW32 X1, VW32 Y1, std::uint8_t* out);
#endif  // HWY_TARGET == HWY_AVX3_DL

#endif  // HWY_TARGET != HWY_SCALAR
// NOLINTNEXTLINE(google-readability-namespace-comments)
}  // namespace HWY_NAMESPACE
}  // namespace rsd::dsp::rectify_detail
HWY_AFTER_NAMESPACE();
#endif  // RSD_DSP_RECTIFY_BILINEAR_EIGHT_INL_H_
