#include "dsp/rectify/rs_rectifier.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define RSD_HAVE_AVX2_KERNELS 1
#endif

namespace rsd::dsp {

namespace {

// Source positions are 16.16 fixed point in the row buffers; a node further than kLimit px
// from the origin is treated as having no solution, so that every value, and every
// difference of two, stays inside int32.
constexpr double kLimit = 8192.0;
constexpr std::int32_t kSentinel = -(1 << 30);  // -16384 px: all four taps outside
constexpr double kFix = 65536.0;

enum CellMode : std::uint8_t { kZero, kPlane, kInfinite, kKink };

// Round to nearest (half away from zero) by truncation: inline, unlike lrint without -fno-math-errno.
std::int32_t to_fixed(double v) { return static_cast<std::int32_t>(v * kFix + std::copysign(0.5, v)); }

bool is_power_of_two(int s) { return s > 0 && (s & (s - 1)) == 0; }

int log2_int(int s) {
  int k = 0;
  while ((1 << k) < s) ++k;
  return k;
}

// ---- Bilinear sampling, fixed point ----------------------------------------------------
//
// A position (16.16) is rounded to 1/256 px: integer tap x0 and 8-bit weight fx. The blend
// rounds after each direction, top = (p00 (256 - fx) + p01 fx + 128) >> 8, then
// out = (top (256 - fy) + bot fy + 128) >> 8: for 8-bit pixels every intermediate fits 16 bits,
// which lets the AVX2 kernel work on 16 pixels per instruction. The scalar code computes the
// same integers, so both paths agree bit for bit; the result is within 1 grey level of exact
// bilinear interpolation at the rounded position. A tap outside the image reads 0 (black).

struct Tap {
  int x0, y0;
  std::uint32_t fx, fy;
};

inline Tap tap(std::int32_t xs, std::int32_t ys) {
  const std::int32_t x8 = (xs + 128) >> 8, y8 = (ys + 128) >> 8;
  return {x8 >> 8, y8 >> 8, static_cast<std::uint32_t>(x8 & 255), static_cast<std::uint32_t>(y8 & 255)};
}

inline std::uint32_t blend(std::uint32_t p00, std::uint32_t p01, std::uint32_t p10, std::uint32_t p11,
                           std::uint32_t fx, std::uint32_t fy) {
  const std::uint32_t top = (p00 * (256 - fx) + p01 * fx + 128) >> 8, bot = (p10 * (256 - fx) + p11 * fx + 128) >> 8;
  return (top * (256 - fy) + bot * fy + 128) >> 8;
}

// memcpy: 16-bit rows need not be 2-byte aligned.
template <class T>
inline std::uint32_t load(const std::uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <class T>
inline void store(std::uint8_t* p, std::uint32_t v) {
  const T t = static_cast<T>(v);
  std::memcpy(p, &t, sizeof(T));
}

template <class T, int C>
inline std::uint32_t texel(const ImageView& src, int x, int y, int c) {
  if (x < 0 || y < 0 || x >= src.width || y >= src.height) return 0;
  return load<T>(src.row(y) + (C * x + c) * sizeof(T));
}

template <class T, int C>
void sample_border(const ImageView& src, const Tap& t, std::uint8_t* out) {
  for (int c = 0; c < C; ++c) {
    const std::uint32_t v =
        blend(texel<T, C>(src, t.x0, t.y0, c), texel<T, C>(src, t.x0 + 1, t.y0, c),
              texel<T, C>(src, t.x0, t.y0 + 1, c), texel<T, C>(src, t.x0 + 1, t.y0 + 1, c), t.fx, t.fy);
    store<T>(out + c * sizeof(T), v);
  }
}

template <class T, int C>
inline void sample_pixel(const ImageView& src, std::int32_t xs, std::int32_t ys, std::uint8_t* out) {
  const Tap t = tap(xs, ys);
  if (t.x0 < 0 || t.y0 < 0 || t.x0 >= src.width - 1 || t.y0 >= src.height - 1) {
    sample_border<T, C>(src, t, out);
    return;
  }
  const std::uint8_t* r0 = src.row(t.y0) + C * t.x0 * sizeof(T);
  const std::uint8_t* r1 = r0 + src.stride;
  constexpr int kNext = C * sizeof(T);
  for (int c = 0; c < C; ++c) {
    const int o = c * sizeof(T);
    store<T>(out + o, blend(load<T>(r0 + o), load<T>(r0 + kNext + o), load<T>(r1 + o),
                            load<T>(r1 + kNext + o), t.fx, t.fy));
  }
}

template <class T, int C>
void sample_row_scalar(const ImageView& src, const std::int32_t* xs, const std::int32_t* ys,
                       std::uint8_t* out, int n) {
  for (int i = 0; i < n; ++i) sample_pixel<T, C>(src, xs[i], ys[i], out + i * C * sizeof(T));
}

// Source positions along one cell of a row are affine in x: x_k = ax + k sx (16.16).
using Affine = Rectifier::Affine;

template <class T, int C>
void sample_affine_scalar(const ImageView& src, const Affine& a, std::uint8_t* out, int n) {
  std::int32_t x = a.ax, y = a.ay;
  for (int i = 0; i < n; ++i, x += a.sx, y += a.sy) sample_pixel<T, C>(src, x, y, out + i * C * sizeof(T));
}

#ifdef RSD_HAVE_AVX2_KERNELS
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
#endif  // RSD_HAVE_AVX2_KERNELS

struct Samplers {
  void (*row)(const ImageView&, const std::int32_t*, const std::int32_t*, std::uint8_t*, int);
  void (*affine)(const ImageView&, const Affine&, std::uint8_t*, int);
};

template <class T, int C>
Samplers scalar_samplers() {
  return {sample_row_scalar<T, C>, sample_affine_scalar<T, C>};
}

Samplers pick_samplers(PixelFormat f, bool simd) {
#ifdef RSD_HAVE_AVX2_KERNELS
  if (simd) {
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
  }
#else
  (void)simd;
#endif
  switch (f) {
    case PixelFormat::Mono8: return scalar_samplers<std::uint8_t, 1>();
    case PixelFormat::Mono16: return scalar_samplers<std::uint16_t, 1>();
    case PixelFormat::Rgb8: return scalar_samplers<std::uint8_t, 3>();
  }
  return {};
}

bool cpu_has_avx2() {
#ifdef RSD_HAVE_AVX2_KERNELS
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

bool finite(const Twist& tw) { return tw.v.allFinite() && tw.w.allFinite(); }

bool same_geometry(const CameraModel& a, const CameraModel& b) {
  return a.width == b.width && a.height == b.height && a.fx == b.fx && a.fy == b.fy && a.cx == b.cx &&
         a.cy == b.cy && a.dist.k1 == b.dist.k1 && a.dist.k2 == b.dist.k2 && a.dist.p1 == b.dist.p1 &&
         a.dist.p2 == b.dist.p2 && a.dist.k3 == b.dist.k3;
}

}  // namespace

double reference_time(const RowTiming& timing, ReferenceRow ref) {
  if (ref == ReferenceRow::First) return timing.row_time(timing.first_row_read());
  return timing.row_time(0.5 * (timing.height - 1));
}

DepthModel ground_plane(double camera_height_m) {
  return DepthModel::plane(Eigen::Vector3d::UnitY(), camera_height_m);
}

// ---- Construction: everything the frames will need is allocated here -------------------

Rectifier::Rectifier(const CameraModel& cam, const RowTiming& timing, PixelFormat format,
                     const RectifierConfig& cfg)
    : Rectifier(cam, timing, cam, format, cfg) {}

Rectifier::Rectifier(const CameraModel& cam, const RowTiming& timing, const CameraModel& out_cam,
                     PixelFormat format, const RectifierConfig& cfg)
    : cam_(cam), out_(out_cam), timing_(timing), format_(format), cfg_(cfg) {
  if (cam.height != timing.height) throw std::invalid_argument("Rectifier: camera and row timing heights differ");
  for (const CameraModel* c : {&cam_, &out_})
    if (c->width < 4 || c->height < 4 || c->width > 8000 || c->height > 8000)
      throw std::invalid_argument("Rectifier: image sizes must be 4..8000 px");
  if (!is_power_of_two(cfg.initial_spacing) || !is_power_of_two(cfg.min_spacing) || cfg.min_spacing < 2 ||
      cfg.min_spacing > cfg.initial_spacing)
    throw std::invalid_argument("Rectifier: spacings must be powers of two, 2 <= min_spacing <= initial_spacing");
  if (!(cfg.tolerance_px > 0) || cfg.table_step_rows < 1)
    throw std::invalid_argument("Rectifier: tolerance must be positive and the table step at least one row");
  allocate_levels();
  // Pose table over the capture window of rs_projection.hpp: rows -H/2 .. 1.5 H - 1.
  // Room for a step of one row: fast motions refine the table as well as the grid.
  table_v0_ = -0.5 * timing_.height;
  table_.resize(2 * static_cast<std::size_t>(timing_.height));
  simd_ = cfg_.use_simd && cpu_has_avx2();
  const Samplers k = pick_samplers(format_, simd_);
  sample_row_ = k.row;
  sample_affine_ = k.affine;
  xs_.assign(out_.width, 0);
  ys_.assign(out_.width, 0);
}

// Levels from the initial spacing down to the minimum; a level needs three nodes each way for
// the second differences. The unit-z rays of the node pixels do not depend on the motion.
void Rectifier::allocate_levels() {
  std::size_t most = 0;
  int widest = 0;
  for (int s = cfg_.initial_spacing; s >= cfg_.min_spacing; s /= 2) {
    Level L;
    L.spacing = s, L.shift = log2_int(s);
    L.nx = (out_.width - 1 + s - 1) / s + 1, L.ny = (out_.height - 1 + s - 1) / s + 1;
    if (L.nx < 3 || L.ny < 3) continue;
    const std::size_t n = static_cast<std::size_t>(L.nx) * L.ny;
    L.ray_x.resize(n), L.ray_y.resize(n), L.ray_ok.resize(n);
    for (int j = 0; j < L.ny; ++j)
      for (int i = 0; i < L.nx; ++i) {
        const std::size_t k = static_cast<std::size_t>(j) * L.nx + i;
        const auto r = out_.ray(Eigen::Vector2d(i * s, j * s));
        L.ray_ok[k] = r.has_value();
        L.ray_x[k] = r ? r->x() : 0, L.ray_y[k] = r ? r->y() : 0;
      }
    most = std::max(most, n), widest = std::max(widest, L.nx);
    levels_.push_back(std::move(L));
  }
  if (levels_.empty()) throw std::invalid_argument("Rectifier: output too small for min_spacing");
  for (Branch* b : {&plane_b_, &inf_b_}) {
    b->x.resize(most), b->y.resize(most), b->ok.resize(most);
    b->d2x.resize(2 * most), b->d2y.resize(2 * most);
  }
  rho_.resize(most);
  cell_mode_.resize(most);
  for (auto* v : {&row_px_, &row_py_, &row_ix_, &row_iy_, &row_rho_, &v_start_}) v->resize(widest);
}

// ---- The exact map at one node ---------------------------------------------------------

// Poses at rows v_k = v_lo + k m, and their increments: between two entries the pose is
// interpolated linearly in the row, an error bounded from the table's second differences.
void Rectifier::build_pose_table(const CameraMotion& motion, int step_rows) {
  const double m = step_rows;
  table_inv_step_ = 1.0 / m;
  table_n_ = static_cast<std::size_t>(std::ceil((2.0 * timing_.height - 1) / m)) + 1;
  for (std::size_t k = 0; k < table_n_; ++k) {
    const Eigen::Affine3d g = motion.at(timing_.row_time(table_v0_ + k * m));
    Pose& P = table_[k];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) P.R[3 * r + c] = g.linear()(r, c);
      P.T[r] = g.translation()(r);
    }
  }
  table_d2R_ = table_d2T_ = 0;
  for (std::size_t k = 0; k + 1 < table_n_; ++k) {
    Pose& P = table_[k];
    const Pose& Q = table_[k + 1];
    for (int e = 0; e < 9; ++e) P.dR[e] = Q.R[e] - P.R[e];
    for (int e = 0; e < 3; ++e) P.dT[e] = Q.T[e] - P.T[e];
  }
  for (std::size_t k = 1; k + 1 < table_n_; ++k) {
    double r2 = 0, t2 = 0;
    for (int e = 0; e < 9; ++e) r2 += std::pow(table_[k].dR[e] - table_[k - 1].dR[e], 2);
    for (int e = 0; e < 3; ++e) t2 += std::pow(table_[k].dT[e] - table_[k - 1].dT[e], 2);
    table_d2R_ = std::max(table_d2R_, std::sqrt(r2)), table_d2T_ = std::max(table_d2T_, std::sqrt(t2));
  }
  std::memset(table_[table_n_ - 1].dR, 0, sizeof table_[0].dR);
  std::memset(table_[table_n_ - 1].dT, 0, sizeof table_[0].dT);
}

// Newton's method on the rolling-shutter constraint eq. (3), in rows:
//     F(v) = pi_y(P(t(v)) X) - v = 0,   t(v) = (v + v0) / r   (eq. (1)),
// for the homogeneous point X = (Y, rho) of the paper's P^3. v is the start on entry and the
// root on exit; px the pixel there. gain bounds how far the pose table's interpolation error
// can move the result (docs/rectification.md). The root is the one Newton reaches from the
// start (the node's neighbour): unique while the image moves slower than the readout.
bool Rectifier::solve_node(const double* Y, double rho, double& v, double* px, double* gain) const {
  const double last = static_cast<double>(table_n_ - 1);
  const bool distorted = !cam_.dist.is_zero();
  for (int it = 0; it < 20; ++it) {
    const double u = (v - table_v0_) * table_inv_step_;
    if (!(u >= 0 && u <= last)) return false;  // outside the capture window
    const int k = std::min(static_cast<int>(u), static_cast<int>(last) - 1);
    const double a = u - k;
    const Pose& P = table_[k];
    double X[3], dX[3];
    for (int r = 0; r < 3; ++r) {
      const double* R = P.R + 3 * r;
      const double* dR = P.dR + 3 * r;
      const double inc = dR[0] * Y[0] + dR[1] * Y[1] + dR[2] * Y[2] + rho * P.dT[r];
      X[r] = R[0] * Y[0] + R[1] * Y[1] + R[2] * Y[2] + rho * P.T[r] + a * inc;
      dX[r] = inc * table_inv_step_;
    }
    if (!(X[2] > 0)) return false;  // behind the camera at that instant
    const double iz = 1.0 / X[2];
    Eigen::Vector2d xn(X[0] * iz, X[1] * iz), dxn((dX[0] - xn.x() * dX[2]) * iz, (dX[1] - xn.y() * dX[2]) * iz);
    if (distorted) {
      dxn = cam_.distort_jacobian(xn) * dxn;
      xn = cam_.distort(xn);
    }
    const double pu = cam_.fx * xn.x() + cam_.cx, pv = cam_.fy * xn.y() + cam_.cy;
    const double du = cam_.fx * dxn.x(), dF = cam_.fy * dxn.y() - 1.0;
    if (!(std::abs(dF) > 1e-3)) return false;  // the image runs with the readout
    const double step = -(pv - v) / dF;
    v += step;
    if (std::abs(step) < 1e-7) {
      px[0] = pu + du * step, px[1] = pv + (dF + 1.0) * step;
      const double ny = std::sqrt(Y[0] * Y[0] + Y[1] * Y[1] + Y[2] * Y[2]);
      *gain = (1 + std::abs(X[0] * iz) + std::abs(X[1] * iz)) * iz * (1 + (1 + std::abs(du)) / std::abs(dF)) *
              (table_d2R_ * ny + table_d2T_ * std::abs(rho));
      return std::abs(px[0]) <= kLimit && std::abs(px[1]) <= kLimit;
    }
  }
  return false;
}

// Every node of the current level for one depth choice: the plane (signed inverse depth, so
// that the map continues smoothly past the horizon) or infinity. Warm start: the solution of
// the node above, one spacing on; nodes of a row do not depend on each other, so the CPU
// overlaps their Newton iterations.
void Rectifier::solve_branch(Branch& b, bool plane_branch) {
  const Level& L = levels_[level_];
  for (int i = 0; i < L.nx; ++i) v_start_[i] = 0;
  for (int j = 0; j < L.ny; ++j)
    for (int i = 0; i < L.nx; ++i) {
      const std::size_t n = static_cast<std::size_t>(j) * L.nx + i;
      b.ok[n] = 0, b.x[n] = b.y[n] = 0;
      double& v = v_start_[i];
      v += L.spacing * (j > 0);
      if (!L.ray_ok[n]) continue;
      const double r[3] = {L.ray_x[n], L.ray_y[n], 1.0};
      const double rho = plane_branch ? rho_[n] : 0.0;
      double Y[3];
      for (int e = 0; e < 3; ++e)
        Y[e] = Rt_ref_[3 * e] * r[0] + Rt_ref_[3 * e + 1] * r[1] + Rt_ref_[3 * e + 2] * r[2] + rho * o_ref_[e];
      double root = v, px[2], gain = 0;
      if (!solve_node(Y, rho, root, px, &gain)) continue;
      b.x[n] = px[0], b.y[n] = px[1], b.ok[n] = 1, v = root;
      gain_max_ = std::max(gain_max_, gain);
    }
  second_differences(b);
}

// |second difference| of the node values along x and y (vector norms), centred at the node or,
// on the grid's edge, at its inward neighbour; NaN where a stencil node has no solution.
void Rectifier::second_differences(Branch& b) const {
  const Level& L = levels_[level_];
  const float nan = std::numeric_limits<float>::quiet_NaN();
  auto d2 = [&](std::size_t a, std::size_t c, std::size_t e, float* out) {
    if (!b.ok[a] || !b.ok[c] || !b.ok[e]) {
      out[0] = out[1] = nan;
      return;
    }
    out[0] = static_cast<float>(b.x[a] - 2 * b.x[c] + b.x[e]);
    out[1] = static_cast<float>(b.y[a] - 2 * b.y[c] + b.y[e]);
  };
  for (int j = 0; j < L.ny; ++j)
    for (int i = 0; i < L.nx; ++i) {
      const std::size_t n = static_cast<std::size_t>(j) * L.nx + i;
      const int ic = std::clamp(i, 1, L.nx - 2), jc = std::clamp(j, 1, L.ny - 2);
      const std::size_t cx = static_cast<std::size_t>(j) * L.nx + ic, cy = static_cast<std::size_t>(jc) * L.nx + i;
      d2(cx - 1, cx, cx + 1, &b.d2x[2 * n]);
      d2(cy - L.nx, cy, cy + L.nx, &b.d2y[2 * n]);
    }
}

// ---- The error bound and the grid's refinement -----------------------------------------

// Bilinear interpolation on an s x s cell errs by at most s^2/8 (max|f_xx| + max|f_yy|)
// (linear interpolation's Peano-kernel bound, once per direction; holds for vector f). The
// maxima over the cell are estimated from the second differences at its corners, s^2 times
// f'' averaged over +-s: the larger of the two corners' values plus their difference (the
// third-derivative term that the averaging can hide).
double Rectifier::cell_bound(const Branch& b, int i, int j) const {
  const Level& L = levels_[level_];
  auto norm = [](float x, float y) { return std::sqrt(x * x + y * y); };
  auto term = [&](const float* a, const float* c) {
    const double t = std::max(norm(a[0], a[1]), norm(c[0], c[1])) + norm(a[0] - c[0], a[1] - c[1]);
    return std::isnan(t) ? std::numeric_limits<double>::infinity() : t;
  };
  const std::size_t n00 = static_cast<std::size_t>(j) * L.nx + i, n01 = n00 + L.nx;
  const double mx = std::max(term(&b.d2x[2 * n00], &b.d2x[2 * n00 + 2]), term(&b.d2x[2 * n01], &b.d2x[2 * n01 + 2]));
  const double my = std::max(term(&b.d2y[2 * n00], &b.d2y[2 * n01]), term(&b.d2y[2 * n00 + 2], &b.d2y[2 * n01 + 2]));
  return (mx + my) / 8.0;
}

namespace {

// True when all four corners of a cell lie more than 2 px beyond one image edge: every
// interpolated position in between does too, so every tap is outside and the cell is black.
bool beyond_one_edge(const Rectifier::Branch& b, const std::size_t* c, int width, int height) {
  bool left = true, right = true, up = true, down = true;
  for (int k = 0; k < 4; ++k) {
    left = left && b.x[c[k]] < -2, right = right && b.x[c[k]] > width + 1;
    up = up && b.y[c[k]] < -2, down = down && b.y[c[k]] > height + 1;
  }
  return left || right || up || down;
}

bool all_ok(const Rectifier::Branch& b, const std::size_t* c) {
  return b.ok[c[0]] && b.ok[c[1]] && b.ok[c[2]] && b.ok[c[3]];
}

}  // namespace

// Classifies every cell (which depth branch it interpolates, or black) and returns the bound
// over the cells that are sampled: interpolation + pose table + fixed-point rounding.
RectifyReport Rectifier::assess_level() {
  const Level& L = levels_[level_];
  RectifyReport rep;
  rep.spacing = L.spacing, rep.tolerance_px = cfg_.tolerance_px;
  double worst = 0;
  for (int j = 0; j + 1 < L.ny; ++j)
    for (int i = 0; i + 1 < L.nx; ++i) {
      const std::size_t n = static_cast<std::size_t>(j) * L.nx + i;
      const std::size_t c[4] = {n, n + 1, n + L.nx, n + L.nx + 1};
      int positive = 0;
      for (std::size_t k : c) positive += plane_ && rho_[k] > 0;
      const bool use_plane = positive > 0, use_inf = positive < 4;
      std::uint8_t mode = use_plane ? (use_inf ? kKink : kPlane) : kInfinite;
      if ((use_plane && !all_ok(plane_b_, c)) || (use_inf && !all_ok(inf_b_, c))) mode = kZero;
      if (mode == kPlane && beyond_one_edge(plane_b_, c, cam_.width, cam_.height)) mode = kZero;
      if (mode == kInfinite && beyond_one_edge(inf_b_, c, cam_.width, cam_.height)) mode = kZero;
      cell_mode_[static_cast<std::size_t>(j) * (L.nx - 1) + i] = mode;
      if (mode == kZero) continue;
      double e = 0;
      if (use_plane) e = std::max(e, cell_bound(plane_b_, i, j));
      if (use_inf) e = std::max(e, cell_bound(inf_b_, i, j));
      if (std::isinf(e)) ++rep.unbounded_cells;
      worst = std::max(worst, e);
    }
  for (std::size_t n = 0; n < static_cast<std::size_t>(L.nx) * L.ny; ++n)  // the branch the model means
    rep.invalid_nodes += !(plane_ && rho_[n] > 0 ? plane_b_.ok[n] : inf_b_.ok[n]);
  // Table: linear interpolation errs by 1/8 of a second difference (times the node's gain).
  table_error_px_ = std::max(cam_.fx, cam_.fy) / 8.0 * gain_max_;
  // Fixed point: rounding to 1/256 px, plus the 16.16 step's rounding accumulated over a cell.
  const double fixed = std::sqrt(2.0) * (1.0 / 512 + (L.spacing + 1) / 131072.0);
  rep.error_bound_px = worst + table_error_px_ + fixed;
  return rep;
}

RectifyReport Rectifier::build_map(const CameraMotion& motion, const DepthModel& depth, double t_ref) {
  // The camera at t_ref: X_c = A X + b, so its rays are A^-1 r from the centre o = -A^-1 b.
  const Eigen::Affine3d g = motion.at(t_ref);
  const Eigen::Matrix3d Ainv = g.linear().inverse();
  const Eigen::Vector3d o = -(Ainv * g.translation());
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Rt_ref_[3 * r + c] = Ainv(r, c);
    o_ref_[r] = o(r);
  }
  // A point of the plane n.X = d on the ray o + lambda a has inverse depth rho = 1/lambda =
  // n.a / (d - n.o): homogeneous X = (a + rho o, rho). rho <= 0 (no hit ahead) -> infinity.
  plane_ = !depth.infinite && std::abs(depth.distance - depth.normal.dot(o)) > 1e-12;
  plane_den_ = plane_ ? depth.distance - depth.normal.dot(o) : 1.0;
  for (int e = 0; e < 3; ++e) plane_n_[e] = depth.normal(e);
  // The grid is refined until the bound holds; the pose table too, where its share is large
  // (only for very fast motion: its error grows with the square of the rotation per step).
  RectifyReport rep;
  for (int step = std::min(cfg_.table_step_rows, timing_.height);; step = std::max(1, step / 2)) {
    build_pose_table(motion, step);
    for (level_ = 0;; ++level_) {
      rep = solve_level();
      if (rep.error_bound_px <= cfg_.tolerance_px || level_ + 1 == levels_.size()) break;
    }
    if (table_error_px_ <= 0.25 * cfg_.tolerance_px || step == 1) break;
  }
  map_ready_ = true;
  rep.rectified = true;
  return rep;
}

RectifyReport Rectifier::solve_level() {
  const Level& L = levels_[level_];
  const std::size_t n_nodes = static_cast<std::size_t>(L.nx) * L.ny;
  need_infinite_ = !plane_;
  for (std::size_t n = 0; n < n_nodes; ++n) {
    const double a[3] = {L.ray_x[n], L.ray_y[n], 1.0};
    double na = 0;
    for (int e = 0; e < 3; ++e)
      na += plane_n_[e] * (Rt_ref_[3 * e] * a[0] + Rt_ref_[3 * e + 1] * a[1] + Rt_ref_[3 * e + 2] * a[2]);
    rho_[n] = plane_ ? na / plane_den_ : 0.0;
    need_infinite_ = need_infinite_ || (L.ray_ok[n] && rho_[n] <= 0);
  }
  gain_max_ = 0;
  if (!need_infinite_) std::fill_n(inf_b_.ok.begin(), n_nodes, std::uint8_t{0});
  if (plane_) solve_branch(plane_b_, true);
  if (need_infinite_) solve_branch(inf_b_, false);
  return assess_level();
}

// ---- Per-row source positions and resampling ---------------------------------------------

namespace {

// 16.16 start and per-pixel step of a cell segment from its two ends (one cell apart).
Affine affine_between(double x_l, double y_l, double x_r, double y_r, int shift) {
  const std::int32_t ax = to_fixed(x_l), ay = to_fixed(y_l);
  const std::int64_t half = (std::int64_t{1} << shift) >> 1;
  return {ax, ay, static_cast<std::int32_t>((std::int64_t{to_fixed(x_r)} - ax + half) >> shift),
          static_cast<std::int32_t>((std::int64_t{to_fixed(y_r)} - ay + half) >> shift)};
}

void linear_segment(const Affine& a, std::int32_t* xs, std::int32_t* ys, int count) {
  std::int32_t x = a.ax, y = a.ay;  // running sums: a vector induction, no multiplies
  for (int k = 0; k < count; ++k, x += a.sx, y += a.sy) xs[k] = x, ys[k] = y;
}

}  // namespace

// The node columns interpolated to row y (linear in y between two node rows); returns the
// cell row.
int Rectifier::interpolate_row(int y) {
  const Level& L = levels_[level_];
  const int j = std::min(y >> L.shift, L.ny - 2);
  const double wy = static_cast<double>(y - j * L.spacing) / L.spacing;
  const std::size_t top = static_cast<std::size_t>(j) * L.nx, bot = top + L.nx;
  auto lerp = [wy](const std::vector<double>& v, std::size_t a, std::size_t b) { return v[a] + wy * (v[b] - v[a]); };
  for (int i = 0; i < L.nx; ++i) {
    if (plane_) row_px_[i] = lerp(plane_b_.x, top + i, bot + i), row_py_[i] = lerp(plane_b_.y, top + i, bot + i);
    if (need_infinite_) row_ix_[i] = lerp(inf_b_.x, top + i, bot + i), row_iy_[i] = lerp(inf_b_.y, top + i, bot + i);
    row_rho_[i] = lerp(rho_, top + i, bot + i);
  }
  return j;
}

Rectifier::Affine Rectifier::cell_affine(int i, std::uint8_t mode) const {
  const std::vector<double>& X = mode == kPlane ? row_px_ : row_ix_;
  const std::vector<double>& Y = mode == kPlane ? row_py_ : row_iy_;
  return affine_between(X[i], Y[i], X[i + 1], Y[i + 1], levels_[level_].shift);
}

// Row y's source positions into xs_, ys_ (16.16; kSentinel where the output is black).
void Rectifier::generate_row(int y) {
  const Level& L = levels_[level_];
  const std::uint8_t* modes = &cell_mode_[static_cast<std::size_t>(interpolate_row(y)) * (L.nx - 1)];
  for (int i = 0; i + 1 < L.nx && i * L.spacing < out_.width; ++i) {
    const int x0 = i * L.spacing, count = std::min(L.spacing, out_.width - x0);
    if (modes[i] == kZero)
      std::fill_n(&xs_[x0], count, kSentinel), std::fill_n(&ys_[x0], count, kSentinel);
    else if (modes[i] == kKink)
      kink_segment(i, x0, count);
    else
      linear_segment(cell_affine(i, modes[i]), &xs_[x0], &ys_[x0], count);
  }
}

// A cell the horizon crosses: both branches are smooth there, so each is interpolated and the
// sign of the (interpolated) inverse depth picks, per pixel, the one the depth model means.
void Rectifier::kink_segment(int i, int x0, int count) {
  const double s = levels_[level_].spacing;
  for (int k = 0; k < count; ++k) {
    const double a = k / s;
    const bool plane = row_rho_[i] + a * (row_rho_[i + 1] - row_rho_[i]) > 0;
    const std::vector<double>& X = plane ? row_px_ : row_ix_;
    const std::vector<double>& Y = plane ? row_py_ : row_iy_;
    xs_[x0 + k] = to_fixed(X[i] + a * (X[i + 1] - X[i]));
    ys_[x0 + k] = to_fixed(Y[i] + a * (Y[i + 1] - Y[i]));
  }
}

// Cells of 16 px and more are sampled straight from their affine positions; narrower cells
// go through the row arrays, so that the kernels still see runs of 16 pixels.
void Rectifier::remap(const ImageView& src, const ImageView& dst) {
  if (!map_ready_) throw std::logic_error("Rectifier::remap: no map built");
  check_views(src, dst);
  const Level& L = levels_[level_];
  const int bpp = bytes_per_pixel(format_);
  for (int y = 0; y < out_.height; ++y) {
    std::uint8_t* out = dst.row(y);
    if (L.spacing < 16) {
      generate_row(y);
      sample_row_(src, xs_.data(), ys_.data(), out, out_.width);
      continue;
    }
    const std::uint8_t* modes = &cell_mode_[static_cast<std::size_t>(interpolate_row(y)) * (L.nx - 1)];
    for (int i = 0; i + 1 < L.nx && i * L.spacing < out_.width; ++i) {
      const int x0 = i * L.spacing, count = std::min(L.spacing, out_.width - x0);
      if (modes[i] == kZero) {
        std::memset(out + x0 * bpp, 0, static_cast<std::size_t>(count) * bpp);
      } else if (modes[i] == kKink) {
        kink_segment(i, x0, count);
        sample_row_(src, &xs_[x0], &ys_[x0], out + x0 * bpp, count);
      } else {
        sample_affine_(src, cell_affine(i, modes[i]), out + x0 * bpp, count);
      }
    }
  }
}

void Rectifier::map_row(int y, double* sx, double* sy) {
  if (!map_ready_) throw std::logic_error("Rectifier::map_row: no map built");
  generate_row(y);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int x = 0; x < out_.width; ++x) {
    sx[x] = xs_[x] == kSentinel ? nan : xs_[x] / kFix;
    sy[x] = ys_[x] == kSentinel ? nan : ys_[x] / kFix;
  }
}

void Rectifier::check_views(const ImageView& src, const ImageView& dst) const {
  if (src.width != cam_.width || src.height != cam_.height || src.format != format_ || !src.data)
    throw std::invalid_argument("Rectifier: source view does not match the camera and format");
  if (dst.width != out_.width || dst.height != out_.height || dst.format != format_ || !dst.data)
    throw std::invalid_argument("Rectifier: destination view does not match the output camera and format");
}

// ---- Entry points ----------------------------------------------------------------------

RectifyReport Rectifier::rectify(const ImageView& src, const ImageView& dst, const Twist& tw,
                                 const DepthModel& depth, double t_ref) {
  if (!finite(tw) || !std::isfinite(t_ref)) return pass_through(src, dst);
  return rectify(src, dst, ScrewMotion(tw), depth, t_ref);
}

RectifyReport Rectifier::rectify(const ImageView& src, const ImageView& dst, const CameraMotion& motion,
                                 const DepthModel& depth, double t_ref) {
  check_views(src, dst);
  const RectifyReport rep = build_map(motion, depth, t_ref);
  remap(src, dst);
  return rep;
}

// Unrectified: a row copy, or through the output camera with no motion at all.
RectifyReport Rectifier::pass_through(const ImageView& src, const ImageView& dst) {
  check_views(src, dst);
  if (!same_geometry(cam_, out_)) {
    RectifyReport rep = build_map(ScrewMotion(Twist{}), DepthModel::at_infinity(), 0.0);
    remap(src, dst);
    rep.rectified = false;
    return rep;
  }
  const std::size_t bytes = static_cast<std::size_t>(src.width) * bytes_per_pixel(format_);
  for (int y = 0; y < src.height; ++y) std::memcpy(dst.row(y), src.row(y), bytes);
  RectifyReport rep;
  rep.tolerance_px = cfg_.tolerance_px;
  return rep;
}

}  // namespace rsd::dsp
