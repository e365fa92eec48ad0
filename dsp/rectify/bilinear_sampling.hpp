// Bilinear sampling of a source image at 16.16 fixed-point positions: the scalar reference
// every kernel must agree with bit for bit (the SIMD kernels, bilinear_sampling_simd.cpp), and
// the choice of kernels for a pixel format at run time.
#pragma once

#include <cstdint>
#include <algorithm>
#include <cstddef>
#include <cstring>
#include <string>
#include <vector>

#include "dsp/core/image_planes.hpp"
#include "dsp/rectify/rs_rectifier.hpp"

namespace rsd::dsp::rectify_detail {

// ---- Bilinear sampling, fixed point ----------------------------------------------------
//
// A position (16.16) is rounded to 1/256 px: integer tap x0 and 8-bit weight fx. The blend
// rounds after each direction, top = (p00 (256 - fx) + p01 fx + 128) >> 8, then
// out = (top (256 - fy) + bot fy + 128) >> 8: for 8-bit pixels every intermediate fits 16 bits,
// which lets the SIMD kernels work on 16 pixels per instruction. The scalar code computes the
// same integers, so both paths agree bit for bit; the result is within 1 grey level of exact
// bilinear interpolation at the rounded position. A tap outside the image reads the plane's
// fill: 0 (black), or 128 for chroma (neutral, so that borders do not turn green).
//
// The kernels resample one sample plane (image_planes.hpp). Packed planes (Mono8, Mono16,
// RGB24, I420's planes, NV12's interleaved U V) have SIMD kernels; the strided planes of YUYV
// and of a Bayer mosaic's sites go through sample_pixel_strided, the same integers with the
// plane's steps.

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
inline std::uint32_t texel(const SamplePlane& src, int x, int y, int c) {
  if (x < 0 || y < 0 || x >= src.width || y >= src.height) return src.fill;
  return load<T>(src.row(y) + (C * x + c) * sizeof(T));
}

template <class T, int C>
inline void sample_border(const SamplePlane& src, const Tap& t, std::uint8_t* out) {
  for (int c = 0; c < C; ++c) {
    const std::uint32_t v =
        blend(texel<T, C>(src, t.x0, t.y0, c), texel<T, C>(src, t.x0 + 1, t.y0, c),
              texel<T, C>(src, t.x0, t.y0 + 1, c), texel<T, C>(src, t.x0 + 1, t.y0 + 1, c), t.fx, t.fy);
    store<T>(out + c * sizeof(T), v);
  }
}

template <class T, int C>
inline void sample_pixel(const SamplePlane& src, std::int32_t xs, std::int32_t ys, std::uint8_t* out) {
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
inline void sample_row_scalar(const SamplePlane& src, const std::int32_t* xs, const std::int32_t* ys,
                       std::uint8_t* out, int n) {
  for (int i = 0; i < n; ++i) sample_pixel<T, C>(src, xs[i], ys[i], out + i * C * sizeof(T));
}

// A plane of any layout: sample x of channel c at x step + c channel_step; the output has the
// same layout (it is the same plane of the destination image).
template <class T>
inline void sample_pixel_strided(const SamplePlane& src, std::int32_t xs, std::int32_t ys, std::uint8_t* out) {
  const Tap t = tap(xs, ys);
  for (int c = 0; c < src.channels; ++c) {
    const int o = c * src.channel_step;
    auto at = [&](int x, int y) -> std::uint32_t {
      if (x < 0 || y < 0 || x >= src.width || y >= src.height) return src.fill;
      return load<T>(src.row(y) + x * src.step + o);
    };
    store<T>(out + o, blend(at(t.x0, t.y0), at(t.x0 + 1, t.y0), at(t.x0, t.y0 + 1), at(t.x0 + 1, t.y0 + 1), t.fx, t.fy));
  }
}

template <class T>
inline void sample_row_strided(const SamplePlane& src, const std::int32_t* xs, const std::int32_t* ys, std::uint8_t* out,
                               int n) {
  for (int i = 0; i < n; ++i) sample_pixel_strided<T>(src, xs[i], ys[i], out + i * src.step);
}

// Source positions along one cell of a row are affine in x: x_k = ax + k sx (16.16).
using Affine = Rectifier::Affine;

template <class T, int C>
inline void sample_affine_scalar(const SamplePlane& src, const Affine& a, std::uint8_t* out, int n) {
  // Running sums in wrapping 32-bit arithmetic (the kernels' lanes wrap alike; a signed int
  // would be undefined where a far segment overflows).
  std::uint32_t x = static_cast<std::uint32_t>(a.ax), y = static_cast<std::uint32_t>(a.ay);
  for (int i = 0; i < n; ++i, x += static_cast<std::uint32_t>(a.sx), y += static_cast<std::uint32_t>(a.sy))
    sample_pixel<T, C>(src, static_cast<std::int32_t>(x), static_cast<std::int32_t>(y), out + i * C * sizeof(T));
}

template <class T>
inline void sample_affine_strided(const SamplePlane& src, const Affine& a, std::uint8_t* out, int n) {
  std::uint32_t x = static_cast<std::uint32_t>(a.ax), y = static_cast<std::uint32_t>(a.ay);
  for (int i = 0; i < n; ++i, x += static_cast<std::uint32_t>(a.sx), y += static_cast<std::uint32_t>(a.sy))
    sample_pixel_strided<T>(src, static_cast<std::int32_t>(x), static_cast<std::int32_t>(y), out + i * src.step);
}

// Whether the taps of samples [0, n) of segment a, as tap() rounds them, lie in columns
// [0, last_x] and rows [0, last_y], with 0 <= sx < sx_end and |sy| below 1/8 row (a block of
// eight samples then spans at most two rows): the SIMD kernels' test, once per cell, that a
// segment's blocks need no checks of their own. The positions are monotone along a segment,
// so its ends bound every tap. Without branches (64-bit compares combined by &): it runs for
// every cell, and a chroma cell is a single step of the kernels on AVX-512.
inline bool segment_within(const Affine& a, int n, std::int32_t sx_end, int last_x, int last_y) {
  const std::int64_t last = n - 1, x1 = a.ax + last * a.sx, y1 = a.ay + last * a.sy;
  const auto in = [](std::int64_t v, int last_tap) {  // 0 <= (v + 128) >> 16 <= last_tap
    return static_cast<std::uint64_t>(v + 128) < static_cast<std::uint64_t>(std::max(last_tap + 1, 0)) << 16;
  };
  const int all = int{n >= 1} & int{static_cast<std::uint32_t>(a.sx) < static_cast<std::uint32_t>(sx_end)} &
                  int{static_cast<std::uint64_t>(std::int64_t{a.sy} + 8191) < 16383} & int{in(a.ax, last_x)} &
                  int{in(x1, last_x)} & int{in(a.ay, last_y)} & int{in(y1, last_y)};
  return all != 0;
}

// A run of consecutive cells of one row: cell k covers the output samples
// [k cell_n, min((k + 1) cell_n, total)) and its positions are affine, a[k] from its first
// sample on. One call per run (not per cell) keeps the per-call set-up out of every cell.
template <class Segment>
inline void for_each_cell(const Affine* a, int cell_n, int total, std::size_t bytes, std::uint8_t* out, Segment segment) {
  for (int c0 = 0, k = 0; c0 < total; c0 += cell_n, ++k) segment(a[k], out + c0 * bytes, std::min(cell_n, total - c0));
}

template <class T, int C>
inline void sample_cells_scalar(const SamplePlane& src, const Affine* a, int cell_n, int total, std::uint8_t* out) {
  for_each_cell(a, cell_n, total, C * sizeof(T), out,
                [&](const Affine& s, std::uint8_t* o, int n) { sample_affine_scalar<T, C>(src, s, o, n); });
}

template <class T>
inline void sample_cells_strided(const SamplePlane& src, const Affine* a, int cell_n, int total, std::uint8_t* out) {
  for_each_cell(a, cell_n, total, src.step, out,
                [&](const Affine& s, std::uint8_t* o, int n) { sample_affine_strided<T>(src, s, o, n); });
}

// The kinds of plane the kernels know: packed 8-bit with 1, 2 or 3 channels, packed 16-bit,
// strided planes of 8 or 16-bit samples, and among those the ones with SIMD kernels too: the
// one-channel 8-bit samples two bytes apart (YUYV's luma, an 8-bit mosaic's sites) and two
// 8-bit channels two bytes apart in four-byte samples (YUYV's U V).
enum class SampleKind { U8, U8x2, U8x3, U16, StridedU8, StridedU16, StridedU8x2, StridedUV4 };
inline constexpr int kSampleKinds = 8;
SampleKind sample_kind(const SamplePlane& p);

// Row samplers for one kind of plane: positions given per pixel, or affine along each cell of
// a run of cells (a single segment: one cell, cell_n = total).
struct Samplers {
  void (*row)(const SamplePlane&, const std::int32_t*, const std::int32_t*, std::uint8_t*, int);
  void (*cells)(const SamplePlane& src, const Affine* a, int cell_n, int total, std::uint8_t* out);
};

// The SIMD kernels of the best target this CPU runs when `simd`, else the scalar reference.
Samplers pick_samplers(SampleKind k, bool simd);

// The scalar reference's kernels.
Samplers scalar_samplers(SampleKind k);
// The SIMD kernels (bilinear_sampling_simd.cpp, Google Highway's runtime dispatch); strided
// kinds get the scalar ones.
Samplers dispatched_samplers(SampleKind k);
// The name of the instruction set the SIMD kernels run on here ("AVX2", "NEON", ...).
std::string simd_target_name();
// For tests: every target compiled in that this CPU runs (Highway's bits, best first), its
// name, and making one of them the only target (0: all again). Not thread-safe.
std::vector<std::int64_t> simd_targets();
std::string target_name(std::int64_t target);
void force_simd_target(std::int64_t target);

}  // namespace rsd::dsp::rectify_detail
