// AVX2 kernels of the bilinear sampler, beside the scalar reference (bilinear_sampling.hpp)
// whose integers they reproduce bit for bit. Compiled for any x86-64 and selected at run time.
#include "dsp/rectify/bilinear_sampling.hpp"

#ifdef RSD_HAVE_AVX2_KERNELS
#include <immintrin.h>

namespace rsd::dsp::rectify_detail {

namespace {

// ---- AVX2 kernels -----------------------------------------------------------------------
//
// Selected at run time (the build does not assume AVX2). Two ways to fetch the taps:
// - windows (Mono8: 16 px, RGB24: 8 px per step): 16-byte loads of the source rows around the
//   step's taps, the taps picked out by pshufb. Used wherever the taps fit, i.e. almost
//   everywhere, since the map is locally close to a translation;
// - gathers (8 px per step): per source row, the 32-bit word at every pixel's left tap, which
//   holds the right tap too (bytes 0..1 for Mono8, both halves for Mono16; RGB needs a second
//   gather at +3); only when all eight taps are at least 3 px inside the right edge, so the
//   4-byte reads never leave the row.
// Steps entirely outside the image store zeros; the rest (near the borders) go to the scalar
// pixel code. Gathers are slow on current cores, hence the windows.
#define RSD_AVX2 __attribute__((target("avx2")))
#define RSD_AVX2_INLINE __attribute__((target("avx2"))) inline

struct Taps8 {
  __m256i x0, y0, fx, fy;
};

// Positions (16.16) -> taps and 8-bit weights, as tap() does.
RSD_AVX2_INLINE Taps8 taps8(__m256i X, __m256i Y) {
  const __m256i half = _mm256_set1_epi32(128), low = _mm256_set1_epi32(255);
  const __m256i x8 = _mm256_srai_epi32(_mm256_add_epi32(X, half), 8);
  const __m256i y8 = _mm256_srai_epi32(_mm256_add_epi32(Y, half), 8);
  return {_mm256_srai_epi32(x8, 8), _mm256_srai_epi32(y8, 8), _mm256_and_si256(x8, low),
          _mm256_and_si256(y8, low)};
}

RSD_AVX2_INLINE __m256i load8(const std::int32_t* p) {
  return _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
}

// 1: all eight in the fast region; -1: all eight entirely outside (black); 0: mixed.
RSD_AVX2_INLINE int classify(const Taps8& t, int width, int height) {
  const __m256i m1 = _mm256_set1_epi32(-1);
  const __m256i in = _mm256_and_si256(
      _mm256_and_si256(_mm256_cmpgt_epi32(t.x0, m1), _mm256_cmpgt_epi32(_mm256_set1_epi32(width - 3), t.x0)),
      _mm256_and_si256(_mm256_cmpgt_epi32(t.y0, m1), _mm256_cmpgt_epi32(_mm256_set1_epi32(height - 1), t.y0)));
  if (_mm256_movemask_epi8(in) == -1) return 1;
  const __m256i out = _mm256_or_si256(
      _mm256_or_si256(_mm256_cmpgt_epi32(m1, t.x0), _mm256_cmpgt_epi32(t.x0, _mm256_set1_epi32(width - 1))),
      _mm256_or_si256(_mm256_cmpgt_epi32(m1, t.y0), _mm256_cmpgt_epi32(t.y0, _mm256_set1_epi32(height - 1))));
  return _mm256_movemask_epi8(out) == -1 ? -1 : 0;
}

// Horizontal weights as 16-bit pairs (256 - fx, fx) for _mm256_madd_epi16.
RSD_AVX2_INLINE __m256i pair_weights(__m256i fx) {
  return _mm256_or_si256(_mm256_sub_epi32(_mm256_set1_epi32(256), fx), _mm256_slli_epi32(fx, 16));
}

// (v + 128) >> 8: the rounding after each direction of the blend, 32-bit lanes.
RSD_AVX2_INLINE __m256i round8(__m256i v) {
  return _mm256_srli_epi32(_mm256_add_epi32(v, _mm256_set1_epi32(128)), 8);
}

// (top (256 - fy) + bot fy + 128) >> 8, as top 256 + (bot - top) fy; 32-bit lanes.
RSD_AVX2_INLINE __m256i vertical(__m256i top, __m256i bot, __m256i fy) {
  return round8(_mm256_add_epi32(_mm256_slli_epi32(top, 8), _mm256_mullo_epi32(_mm256_sub_epi32(bot, top), fy)));
}

RSD_AVX2_INLINE __m256i gather(const std::uint8_t* base, __m256i off) {
  return _mm256_i32gather_epi32(reinterpret_cast<const int*>(base), off, 1);
}

// Mono8: bytes 0 and 1 of each gathered word, widened to 16-bit pairs, times the pair weights.
RSD_AVX2 void mono8_step(const ImageView& src, const Taps8& t, std::uint8_t* out) {
  const __m256i off = _mm256_add_epi32(_mm256_mullo_epi32(t.y0, _mm256_set1_epi32(static_cast<int>(src.stride))), t.x0);
  const __m256i widen = _mm256_setr_epi8(0, -1, 1, -1, 4, -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1,
                                         0, -1, 1, -1, 4, -1, 5, -1, 8, -1, 9, -1, 12, -1, 13, -1);
  const __m256i wx = pair_weights(t.fx);
  const __m256i top = round8(_mm256_madd_epi16(_mm256_shuffle_epi8(gather(src.data, off), widen), wx));
  const __m256i bot = round8(_mm256_madd_epi16(_mm256_shuffle_epi8(gather(src.data + src.stride, off), widen), wx));
  const __m256i v = vertical(top, bot, t.fy);
  const __m256i narrow = _mm256_setr_epi8(0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1,
                                          0, 4, 8, 12, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1);
  const __m256i b = _mm256_shuffle_epi8(v, narrow);
  const __m128i lo = _mm256_castsi256_si128(b), hi = _mm256_extracti128_si256(b, 1);
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out), _mm_unpacklo_epi32(lo, hi));
}

// (p0 (256 - fx) + p1 fx + 128) >> 8 for the 16-bit pair (p0, p1) of each word.
RSD_AVX2_INLINE __m256i horizontal16(__m256i g, __m256i fx) {
  const __m256i p0 = _mm256_and_si256(g, _mm256_set1_epi32(0xFFFF)), p1 = _mm256_srli_epi32(g, 16);
  return round8(_mm256_add_epi32(_mm256_slli_epi32(p0, 8), _mm256_mullo_epi32(_mm256_sub_epi32(p1, p0), fx)));
}

// Mono16: a gathered word is exactly (p00, p01); 32-bit lanes throughout.
RSD_AVX2 void mono16_step(const ImageView& src, const Taps8& t, std::uint8_t* out) {
  const __m256i off = _mm256_add_epi32(_mm256_mullo_epi32(t.y0, _mm256_set1_epi32(static_cast<int>(src.stride))),
                                       _mm256_add_epi32(t.x0, t.x0));
  const __m256i v = vertical(horizontal16(gather(src.data, off), t.fx),
                             horizontal16(gather(src.data + src.stride, off), t.fx), t.fy);
  const __m256i packed = _mm256_permute4x64_epi64(_mm256_packus_epi32(v, v), 0x08);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm256_castsi256_si128(packed));
}

// RGB24: the left and right taps are separate gathers (at 3 x0 and 3 x0 + 3); channel c is
// byte c of each, paired as 16-bit (left, right) for the madd.
RSD_AVX2_INLINE __m256i rgb_channel(__m256i left, __m256i right, __m256i wx, int c) {
  const char a = static_cast<char>(c), b = static_cast<char>(4 + c), d = static_cast<char>(8 + c),
             e = static_cast<char>(12 + c);
  const __m256i ml = _mm256_setr_epi8(a, -1, -1, -1, b, -1, -1, -1, d, -1, -1, -1, e, -1, -1, -1,
                                      a, -1, -1, -1, b, -1, -1, -1, d, -1, -1, -1, e, -1, -1, -1);
  const __m256i mr = _mm256_setr_epi8(-1, -1, a, -1, -1, -1, b, -1, -1, -1, d, -1, -1, -1, e, -1,
                                      -1, -1, a, -1, -1, -1, b, -1, -1, -1, d, -1, -1, -1, e, -1);
  return round8(_mm256_madd_epi16(_mm256_or_si256(_mm256_shuffle_epi8(left, ml), _mm256_shuffle_epi8(right, mr)), wx));
}

// 8 pixels (R | G << 8 | B << 16 per 32-bit lane) -> 24 bytes.
RSD_AVX2_INLINE void store_rgb8(__m256i rgb, std::uint8_t* out) {
  const __m256i pack = _mm256_setr_epi8(0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1,
                                        0, 1, 2, 4, 5, 6, 8, 9, 10, 12, 13, 14, -1, -1, -1, -1);
  const __m256i p = _mm256_shuffle_epi8(rgb, pack);
  // 12 bytes per lane: the first store's 4 spare bytes are overwritten by the second.
  _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm256_castsi256_si128(p));
  const __m128i hi = _mm256_extracti128_si256(p, 1);
  _mm_storel_epi64(reinterpret_cast<__m128i*>(out + 12), hi);
  const std::uint32_t last = static_cast<std::uint32_t>(_mm_extract_epi32(hi, 2));
  std::memcpy(out + 20, &last, 4);
}

RSD_AVX2 void rgb8_step(const ImageView& src, const Taps8& t, std::uint8_t* out) {
  const __m256i off = _mm256_add_epi32(_mm256_mullo_epi32(t.y0, _mm256_set1_epi32(static_cast<int>(src.stride))),
                                       _mm256_add_epi32(t.x0, _mm256_add_epi32(t.x0, t.x0)));
  const std::uint8_t* r0 = src.data;
  const std::uint8_t* r1 = src.data + src.stride;
  const __m256i g00 = gather(r0, off), g01 = gather(r0 + 3, off), g10 = gather(r1, off), g11 = gather(r1 + 3, off);
  const __m256i wx = pair_weights(t.fx);
  __m256i rgb = _mm256_setzero_si256();
  for (int c = 0; c < 3; ++c) {
    const __m256i v = vertical(rgb_channel(g00, g01, wx, c), rgb_channel(g10, g11, wx, c), t.fy);
    rgb = _mm256_or_si256(rgb, _mm256_sllv_epi32(v, _mm256_set1_epi32(8 * c)));
  }
  store_rgb8(rgb, out);
}

// Mono8 without gathers: 16 pixels as two halves of 8, each read through 16-byte windows on
// the source rows y, y + 1 (and y + 2 where the half's taps straddle two rows), starting at
// its first tap x; taken when every pixel of a half lies within 14 px right of x and one row
// below y. That holds almost everywhere, the map being close to a translation. Byte pairs
// (p0, p1) come out of the windows by pshufb and the blend runs on 16-bit lanes.
//
// The positions come interleaved, X0 = pixels 0-3 | 8-11 and X1 = 4-7 | 12-15, so that packing
// 32-bit lanes to 16 bits puts pixels 0-7 in the low 128-bit lane (first half, first window)
// and 8-15 in the high one, with no lane-crossing permutes.
struct Windows {
  int xa, ya, xb, yb;  // window origins of the two halves
};

// Origins from each half's first and last pixel; false when a window leaves the image.
RSD_AVX2_INLINE bool place_windows(const Taps8& t0, const Taps8& t1, int width, int height, Windows& w) {
  const __m128i x0h = _mm256_extracti128_si256(t0.x0, 1), y0h = _mm256_extracti128_si256(t0.y0, 1);
  const __m128i y1l = _mm256_castsi256_si128(t1.y0), y1h = _mm256_extracti128_si256(t1.y0, 1);
  w.xa = _mm256_cvtsi256_si32(t0.x0), w.xb = _mm_cvtsi128_si32(x0h);
  w.ya = std::min(_mm256_cvtsi256_si32(t0.y0), _mm_extract_epi32(y1l, 3));
  w.yb = std::min(_mm_cvtsi128_si32(y0h), _mm_extract_epi32(y1h, 3));
  return std::min(w.xa, w.xb) >= 0 && std::max(w.xa, w.xb) <= width - 16 && std::min(w.ya, w.yb) >= 0 &&
         std::max(w.ya, w.yb) <= height - 2;
}

RSD_AVX2_INLINE __m256i window_pair(const ImageView& src, const Windows& w, int row) {
  const __m128i lo = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src.row(w.ya + row) + w.xa));
  const __m128i hi = _mm_loadu_si128(reinterpret_cast<const __m128i*>(src.row(w.yb + row) + w.xb));
  return _mm256_inserti128_si256(_mm256_castsi128_si256(lo), hi, 1);
}

// (p0 (256 - f) + p1 f + 128) >> 8 on 16-bit lanes holding byte pairs (p0 low, p1 high).
RSD_AVX2_INLINE __m256i blend16(__m256i pairs, __m256i f) {
  const __m256i p0 = _mm256_and_si256(pairs, _mm256_set1_epi16(0xFF)), p1 = _mm256_srli_epi16(pairs, 8);
  const __m256i v = _mm256_add_epi16(_mm256_mullo_epi16(p0, _mm256_sub_epi16(_mm256_set1_epi16(256), f)),
                                     _mm256_mullo_epi16(p1, f));
  return _mm256_srli_epi16(_mm256_add_epi16(v, _mm256_set1_epi16(128)), 8);
}

// Window column pairs (i, i + 1) as 16-bit lanes i | (i + 1) << 8.
RSD_AVX2_INLINE __m256i column_pairs(__m256i i) {
  return _mm256_add_epi32(_mm256_or_si256(i, _mm256_slli_epi32(i, 8)), _mm256_set1_epi32(0x100));
}

// The blend of 16 pixels whose windows are placed and whose taps are known to fit them:
// i0, i1 columns and d0, d1 rows (0 or 1) relative to the windows, interleaved like t0, t1.
RSD_AVX2_INLINE void mono8_windowed(const ImageView& src, const Windows& w, const Taps8& t0, const Taps8& t1,
                                    __m256i i0, __m256i i1, __m256i d0, __m256i d1, bool straddle, std::uint8_t* out) {
  const __m256i idx = _mm256_packs_epi32(column_pairs(i0), column_pairs(i1));
  __m256i up = _mm256_shuffle_epi8(window_pair(src, w, 0), idx);
  __m256i down = _mm256_shuffle_epi8(window_pair(src, w, 1), idx);
  if (straddle) {  // pixels one row lower take rows y + 1, y + 2
    const __m256i c1 = _mm256_set1_epi32(1);
    const __m256i lower = _mm256_packs_epi32(_mm256_cmpeq_epi32(d0, c1), _mm256_cmpeq_epi32(d1, c1));
    up = _mm256_blendv_epi8(up, down, lower);
    down = _mm256_blendv_epi8(down, _mm256_shuffle_epi8(window_pair(src, w, 2), idx), lower);
  }
  const __m256i fx = _mm256_packs_epi32(t0.fx, t1.fx), fy = _mm256_packs_epi32(t0.fy, t1.fy);
  const __m256i top = blend16(up, fx), bot = blend16(down, fx);
  // Vertical: (top (256 - fy) + bot fy + 128) >> 8, again below 2^16.
  const __m256i v = _mm256_srli_epi16(
      _mm256_add_epi16(_mm256_add_epi16(_mm256_mullo_epi16(top, _mm256_sub_epi16(_mm256_set1_epi16(256), fy)),
                                        _mm256_mullo_epi16(bot, fy)),
                       _mm256_set1_epi16(128)),
      8);
  const __m256i bytes = _mm256_permute4x64_epi64(_mm256_packus_epi16(v, v), 0x08);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(out), _mm256_castsi256_si128(bytes));
}

RSD_AVX2_INLINE __m256i per_half(int a, int b) {
  return _mm256_set_m128i(_mm_set1_epi32(b), _mm_set1_epi32(a));
}

RSD_AVX2_INLINE bool mono8_window16(const ImageView& src, const Taps8& t0, const Taps8& t1, std::uint8_t* out) {
  Windows w;
  if (!place_windows(t0, t1, src.width, src.height, w)) return false;
  const __m256i bx = per_half(w.xa, w.xb), by = per_half(w.ya, w.yb);
  const __m256i i0 = _mm256_sub_epi32(t0.x0, bx), i1 = _mm256_sub_epi32(t1.x0, bx);
  const __m256i d0 = _mm256_sub_epi32(t0.y0, by), d1 = _mm256_sub_epi32(t1.y0, by);
  const __m256i c14 = _mm256_set1_epi32(14), c1 = _mm256_set1_epi32(1);
  const __m256i cols = _mm256_and_si256(_mm256_cmpeq_epi32(_mm256_max_epu32(i0, c14), c14),
                                        _mm256_cmpeq_epi32(_mm256_max_epu32(i1, c14), c14));
  const __m256i rows = _mm256_and_si256(_mm256_cmpeq_epi32(_mm256_max_epu32(d0, c1), c1),
                                        _mm256_cmpeq_epi32(_mm256_max_epu32(d1, c1), c1));
  if (_mm256_movemask_epi8(_mm256_and_si256(cols, rows)) != -1) return false;
  const __m256i below = _mm256_or_si256(d0, d1);
  const bool straddle = !_mm256_testz_si256(below, below);
  if (straddle && std::max(w.ya, w.yb) > src.height - 3) return false;
  mono8_windowed(src, w, t0, t1, i0, i1, d0, d1, straddle, out);
  return true;
}

// RGB24 without gathers: 8 pixels, 4 per 128-bit lane, each lane read through 16-byte windows
// (5 px) at its first pixel's left tap on rows y, y + 1 (and y + 2 where it straddles two rows);
// taken when the lane's pixels lie within 3 px right of it and within one row. Channel c of
// the taps comes out as 16-bit pairs (left, right) by pshufb, then the same 32-bit arithmetic
// as the gather kernel.
RSD_AVX2_INLINE bool rgb8_window8(const ImageView& src, const Taps8& t, std::uint8_t* out) {
  const __m128i xlo = _mm256_castsi256_si128(t.x0), xhi = _mm256_extracti128_si256(t.x0, 1);
  const __m128i ylo = _mm256_castsi256_si128(t.y0), yhi = _mm256_extracti128_si256(t.y0, 1);
  const int xa = _mm_cvtsi128_si32(xlo), xb = _mm_cvtsi128_si32(xhi);
  const int ya = std::min(_mm_cvtsi128_si32(ylo), _mm_extract_epi32(ylo, 3));
  const int yb = std::min(_mm_cvtsi128_si32(yhi), _mm_extract_epi32(yhi, 3));
  if (std::min(xa, xb) < 0 || std::max(xa, xb) > src.width - 6 || std::min(ya, yb) < 0 ||
      std::max(ya, yb) > src.height - 2)
    return false;
  const __m256i idx = _mm256_sub_epi32(t.x0, _mm256_setr_epi32(xa, xa, xa, xa, xb, xb, xb, xb));
  const __m256i dy = _mm256_sub_epi32(t.y0, _mm256_setr_epi32(ya, ya, ya, ya, yb, yb, yb, yb));
  const __m256i c3 = _mm256_set1_epi32(3), c1 = _mm256_set1_epi32(1);
  const __m256i ok = _mm256_and_si256(_mm256_cmpeq_epi32(_mm256_max_epu32(idx, c3), c3),
                                      _mm256_cmpeq_epi32(_mm256_max_epu32(dy, c1), c1));
  if (_mm256_movemask_epi8(ok) != -1) return false;
  const __m256i lower = _mm256_cmpeq_epi32(dy, c1);
  const bool straddle = !_mm256_testz_si256(lower, lower);
  if (straddle && std::max(ya, yb) > src.height - 3) return false;
  auto window = [&](int row) RSD_AVX2 {
    const std::uint8_t* a = src.row(ya + row) + 3 * xa;
    const std::uint8_t* b = src.row(yb + row) + 3 * xb;
    return _mm256_inserti128_si256(_mm256_castsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a))),
                                   _mm_loadu_si128(reinterpret_cast<const __m128i*>(b)), 1);
  };
  const __m256i w0 = window(0), w1 = window(1), w2 = straddle ? window(2) : w1;
  // pshufb control per pixel: bytes (3i + c, zero, 3i + 3 + c, zero).
  const __m256i b = _mm256_add_epi32(idx, _mm256_add_epi32(idx, idx));
  const __m256i ctl = _mm256_add_epi32(_mm256_or_si256(b, _mm256_slli_epi32(b, 16)),
                                       _mm256_set1_epi32(static_cast<int>(0x80038000u)));
  const __m256i wx = pair_weights(t.fx);
  __m256i rgb = _mm256_setzero_si256();
  for (int c = 0; c < 3; ++c) {
    const __m256i k = _mm256_add_epi32(ctl, _mm256_set1_epi32(c * 0x10001));
    __m256i up = _mm256_shuffle_epi8(w0, k), down = _mm256_shuffle_epi8(w1, k);
    if (straddle) {
      up = _mm256_blendv_epi8(up, down, lower);
      down = _mm256_blendv_epi8(down, _mm256_shuffle_epi8(w2, k), lower);
    }
    const __m256i v = vertical(round8(_mm256_madd_epi16(up, wx)), round8(_mm256_madd_epi16(down, wx)), t.fy);
    rgb = c == 0 ? v : _mm256_or_si256(rgb, _mm256_sllv_epi32(v, _mm256_set1_epi32(8 * c)));
  }
  store_rgb8(rgb, out);
  return true;
}

// Mono8 on an affine segment whose slope makes the windows fit by construction: with
// 0 <= sx <= 2 px and 7 |sy| < 1 px per pixel, the taps of 8 consecutive pixels are monotonic,
// span at most 14 columns and at most two adjacent rows. Only the windows' placement in the
// image is left to check, from each half's first and last pixel in scalar arithmetic.
RSD_AVX2_INLINE bool mono8_affine16(const ImageView& src, const Affine& a, int i, __m256i X0, __m256i Y0,
                                    __m256i X1, __m256i Y1, std::uint8_t* out) {
  auto tap0 = [](std::int32_t v) { return (v + 128) >> 16; };  // integer tap, as taps8 rounds
  Windows w;
  w.xa = tap0(a.ax + i * a.sx), w.xb = tap0(a.ax + (i + 8) * a.sx);
  const int ya0 = tap0(a.ay + i * a.sy), ya7 = tap0(a.ay + (i + 7) * a.sy);
  const int yb0 = tap0(a.ay + (i + 8) * a.sy), yb7 = tap0(a.ay + (i + 15) * a.sy);
  w.ya = std::min(ya0, ya7), w.yb = std::min(yb0, yb7);
  const bool straddle = ya0 != ya7 || yb0 != yb7;
  if (std::min(w.xa, w.xb) < 0 || std::max(w.xa, w.xb) > src.width - 16 || std::min(w.ya, w.yb) < 0 ||
      std::max(w.ya, w.yb) > src.height - 2 - straddle)
    return false;
  const Taps8 t0 = taps8(X0, Y0), t1 = taps8(X1, Y1);
  const __m256i bx = per_half(w.xa, w.xb), by = per_half(w.ya, w.yb);
  mono8_windowed(src, w, t0, t1, _mm256_sub_epi32(t0.x0, bx), _mm256_sub_epi32(t1.x0, bx),
                 _mm256_sub_epi32(t0.y0, by), _mm256_sub_epi32(t1.y0, by), straddle, out);
  return true;
}

using Window16 = bool (*)(const ImageView&, const Taps8&, const Taps8&, std::uint8_t*);
using Window8 = bool (*)(const ImageView&, const Taps8&, std::uint8_t*);
using Step8 = void (*)(const ImageView&, const Taps8&, std::uint8_t*);

// 8 pixels without windows: gathers, zeros, or the scalar code near the borders.
template <class T, int C, Step8 Step, Window8 Win8>
RSD_AVX2_INLINE void eight(const ImageView& src, __m256i X, __m256i Y, std::uint8_t* out) {
  const Taps8 t = taps8(X, Y);
  if constexpr (Win8 != nullptr)
    if (Win8(src, t, out)) return;
  const int k = classify(t, src.width, src.height);
  if (k > 0) {
    Step(src, t, out);
  } else if (k < 0) {
    std::memset(out, 0, 8 * C * sizeof(T));
  } else {
    alignas(32) std::int32_t xs[8], ys[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(xs), X), _mm256_store_si256(reinterpret_cast<__m256i*>(ys), Y);
    _mm256_zeroupper();  // entering SSE code: dirty upper halves would slow every SSE instruction
    sample_row_scalar<T, C>(src, xs, ys, out, 8);
  }
}

// 16 pixels, positions interleaved as mono8_window16 takes them.
template <class T, int C, Step8 Step, Window8 Win8, Window16 Win16>
RSD_AVX2_INLINE void sixteen(const ImageView& src, __m256i X0, __m256i Y0, __m256i X1, __m256i Y1, std::uint8_t* out) {
  if (Win16(src, taps8(X0, Y0), taps8(X1, Y1), out)) return;
  eight<T, C, Step, Win8>(src, _mm256_permute2x128_si256(X0, X1, 0x20), _mm256_permute2x128_si256(Y0, Y1, 0x20), out);
  eight<T, C, Step, Win8>(src, _mm256_permute2x128_si256(X0, X1, 0x31), _mm256_permute2x128_si256(Y0, Y1, 0x31),
                          out + 8 * C * sizeof(T));
}

// Positions from the row arrays (cells narrower than 16 px, cells the horizon crosses).
template <class T, int C, Step8 Step, Window8 Win8, Window16 Win16>
RSD_AVX2 void sample_row_avx2(const ImageView& src, const std::int32_t* xs, const std::int32_t* ys,
                              std::uint8_t* out, int n) {
  constexpr int kBytes = C * sizeof(T);
  int i = 0;
  if constexpr (Win16 != nullptr)
    for (; i + 16 <= n; i += 16) {
      const __m256i xa = load8(xs + i), xb = load8(xs + i + 8), ya = load8(ys + i), yb = load8(ys + i + 8);
      sixteen<T, C, Step, Win8, Win16>(src, _mm256_permute2x128_si256(xa, xb, 0x20), _mm256_permute2x128_si256(ya, yb, 0x20),
                                       _mm256_permute2x128_si256(xa, xb, 0x31), _mm256_permute2x128_si256(ya, yb, 0x31),
                                       out + i * kBytes);
    }
  for (; i + 8 <= n; i += 8) eight<T, C, Step, Win8>(src, load8(xs + i), load8(ys + i), out + i * kBytes);
  _mm256_zeroupper();
  sample_row_scalar<T, C>(src, xs + i, ys + i, out + i * kBytes, n - i);
}

// Positions generated in registers along an affine cell segment, x_k = ax + k sx: the same
// integers as linear_segment() writes, without the round trip through memory.
template <class T, int C, Step8 Step, Window8 Win8, Window16 Win16>
RSD_AVX2 void sample_affine_avx2(const ImageView& src, const Affine& a, std::uint8_t* out, int n) {
  constexpr int kBytes = C * sizeof(T);
  const __m256i sx = _mm256_set1_epi32(a.sx), sy = _mm256_set1_epi32(a.sy);
  int i = 0;
  if constexpr (Win16 != nullptr) {
    const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 8, 9, 10, 11);  // interleaved halves
    __m256i X = _mm256_add_epi32(_mm256_set1_epi32(a.ax), _mm256_mullo_epi32(lanes, sx));
    __m256i Y = _mm256_add_epi32(_mm256_set1_epi32(a.ay), _mm256_mullo_epi32(lanes, sy));
    const __m256i X4 = _mm256_set1_epi32(4 * a.sx), Y4 = _mm256_set1_epi32(4 * a.sy);
    const __m256i X16 = _mm256_set1_epi32(16 * a.sx), Y16 = _mm256_set1_epi32(16 * a.sy);
    // Slopes for which every half fits its windows by construction (see mono8_affine16).
    const bool fits = a.sx >= 0 && a.sx <= 2 * 65536 && 7 * std::abs(a.sy) < 65536;
    for (; i + 16 <= n; i += 16, X = _mm256_add_epi32(X, X16), Y = _mm256_add_epi32(Y, Y16)) {
      const __m256i X1 = _mm256_add_epi32(X, X4), Y1 = _mm256_add_epi32(Y, Y4);
      if (!fits || !mono8_affine16(src, a, i, X, Y, X1, Y1, out + i * kBytes))
        sixteen<T, C, Step, Win8, Win16>(src, X, Y, X1, Y1, out + i * kBytes);
    }
  }
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  __m256i X = _mm256_add_epi32(_mm256_set1_epi32(a.ax + i * a.sx), _mm256_mullo_epi32(lanes, sx));
  __m256i Y = _mm256_add_epi32(_mm256_set1_epi32(a.ay + i * a.sy), _mm256_mullo_epi32(lanes, sy));
  const __m256i X8 = _mm256_set1_epi32(8 * a.sx), Y8 = _mm256_set1_epi32(8 * a.sy);
  for (; i + 8 <= n; i += 8, X = _mm256_add_epi32(X, X8), Y = _mm256_add_epi32(Y, Y8))
    eight<T, C, Step, Win8>(src, X, Y, out + i * kBytes);
  alignas(32) std::int32_t xs[8], ys[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(xs), X), _mm256_store_si256(reinterpret_cast<__m256i*>(ys), Y);
  _mm256_zeroupper();
  sample_row_scalar<T, C>(src, xs, ys, out + i * kBytes, n - i);
}

}  // namespace

Samplers avx2_samplers(PixelFormat f) {
  switch (f) {
    case PixelFormat::Mono8:
      return {sample_row_avx2<std::uint8_t, 1, mono8_step, nullptr, mono8_window16>,
              sample_affine_avx2<std::uint8_t, 1, mono8_step, nullptr, mono8_window16>};
    case PixelFormat::Mono16:
      return {sample_row_avx2<std::uint16_t, 1, mono16_step, nullptr, nullptr>,
              sample_affine_avx2<std::uint16_t, 1, mono16_step, nullptr, nullptr>};
    case PixelFormat::Rgb8:
      return {sample_row_avx2<std::uint8_t, 3, rgb8_step, rgb8_window8, nullptr>,
              sample_affine_avx2<std::uint8_t, 3, rgb8_step, rgb8_window8, nullptr>};
  }
  return {};
}

}  // namespace rsd::dsp::rectify_detail
#endif  // RSD_HAVE_AVX2_KERNELS
