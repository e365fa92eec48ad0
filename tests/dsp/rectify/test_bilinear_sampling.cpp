// The SIMD kernels of every instruction set compiled in and run by this CPU (x86-64: SSSE3,
// SSE4, AVX2, AVX-512, EMU128; arm64 under qemu: NEON, SVE, SVE2) against the scalar reference,
// byte for byte: positions per pixel and affine cell segments, near-translations (the window
// paths), scattered positions (gathers), the borders and outside (scalar code, zeros), padded
// rows, every length up to a few steps. Bytes after a row's end must stay untouched, and the
// source has no slack after its last row (the sanitizer tree catches any read beyond it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <random>
#include <string>
#include <vector>

#include "dsp/rectify/bilinear_sampling.hpp"
#include "tests/dsp/rectify/simd_targets.hpp"

using namespace rsd::dsp;
using namespace rsd::dsp::rectify_detail;
using namespace rsd::dsp::test;

namespace {

constexpr std::uint8_t kGuard = 0xAB;

// The packed kinds of plane the SIMD kernels handle: Mono8 (and I420's planes), NV12's U V
// pairs, RGB24, Mono16.
struct Kind {
  SampleKind kind;
  int channels, bytes;
  const char* name;
  int pixel_bytes() const { return channels * bytes; }
};
constexpr Kind kPacked[] = {{SampleKind::U8, 1, 1, "Mono8"},
                            {SampleKind::U8x2, 2, 1, "UV8"},
                            {SampleKind::U8x3, 3, 1, "Rgb8"},
                            {SampleKind::U16, 1, 2, "Mono16"}};

struct Source {
  std::vector<std::uint8_t> bytes;
  SamplePlane view;
};

// A random plane whose rows are `pad` bytes longer than its pixels; the buffer ends with the
// last pixel. fill: what lies outside (chroma's 128 for the U V pairs).
Source random_source(int w, int h, const Kind& k, int pad, unsigned seed) {
  Source s;
  const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(w) * k.pixel_bytes();
  s.bytes.resize(static_cast<std::size_t>((row + pad) * (h - 1) + row));
  std::mt19937 rng(seed);
  for (auto& b : s.bytes) b = static_cast<std::uint8_t>(rng());
  s.view.data = s.bytes.data(), s.view.width = w, s.view.height = h, s.view.stride = row + pad;
  s.view.channels = k.channels, s.view.sample_bytes = k.bytes, s.view.step = k.pixel_bytes(), s.view.channel_step = k.bytes;
  s.view.fill = k.channels == 2 ? 128 : 0;
  return s;
}

std::int32_t fixed(double px) { return static_cast<std::int32_t>(std::lround(px * 65536)); }

// A segment's start and slope: mostly near the identity map (windows), some steep or reversed
// (gathers), some starting over a border or outside.
Affine random_affine(std::mt19937& rng, int w, int h) {
  std::uniform_real_distribution<double> u(0, 1);
  const double kind = u(rng);
  double sx = 1 + 0.2 * (u(rng) - 0.5), sy = 0.1 * (u(rng) - 0.5);
  if (kind > 0.7) sx = 6 * (u(rng) - 0.5), sy = 2 * (u(rng) - 0.5);
  const double x = (w + 8) * u(rng) - 4, y = (h + 4) * u(rng) - 2;
  return {fixed(x), fixed(y), fixed(sx), fixed(sy)};
}

struct Positions {
  std::vector<std::int32_t> xs, ys;
};

// Per-pixel positions as the row arrays hold them: a wobbly translation, scattered points, or
// the sentinel (black), per run.
Positions random_positions(std::mt19937& rng, int n, int w, int h) {
  std::uniform_real_distribution<double> u(0, 1);
  Positions p{std::vector<std::int32_t>(n), std::vector<std::int32_t>(n)};
  double x = (w + 8) * u(rng) - 4, y = (h + 4) * u(rng) - 2;
  for (int k = 0; k < n; ++k) {
    const double kind = u(rng);
    if (kind < 0.8) {
      x += 1 + 0.3 * (u(rng) - 0.5), y += 0.2 * (u(rng) - 0.5);
      p.xs[k] = fixed(x), p.ys[k] = fixed(y);
    } else if (kind < 0.95) {
      p.xs[k] = fixed((w + 6) * u(rng) - 3), p.ys[k] = fixed((h + 6) * u(rng) - 3);
    } else {
      p.xs[k] = p.ys[k] = -(1 << 30);
    }
  }
  return p;
}

std::vector<std::uint8_t> guarded(int n, const Kind& k) {
  return std::vector<std::uint8_t>(static_cast<std::size_t>(n) * k.pixel_bytes() + 32, kGuard);
}

// Checks `got` against `want` and that the guard bytes after n pixels are intact.
void expect_same(const std::vector<std::uint8_t>& got, const std::vector<std::uint8_t>& want, int n, const Kind& k,
                 const std::string& what) {
  const std::size_t used = static_cast<std::size_t>(n) * k.pixel_bytes();
  for (std::size_t i = 0; i < got.size(); ++i) {
    const std::uint8_t expected = i < used ? want[i] : kGuard;
    if (got[i] != expected) {
      ADD_FAILURE() << what << ": byte " << i << " of " << used << " is " << int(got[i]) << ", want " << int(expected);
      return;
    }
  }
}

// One affine segment: a run of one cell.
void affine(const Samplers& k, const SamplePlane& src, const Affine& a, std::uint8_t* out, int n) {
  k.cells(src, &a, n, n, out);
}

// One segment of n samples through the SIMD and the reference samplers, compared byte for byte
// (and the guard bytes after it).
void expect_segment_same(const Samplers& simd, const Samplers& ref, const SamplePlane& src, const Affine& a, int n,
                         const Kind& f, const std::string& what) {
  std::vector<std::uint8_t> got = guarded(n, f), want = guarded(n, f);
  affine(simd, src, a, got.data(), n);
  affine(ref, src, a, want.data(), n);
  expect_same(got, want, n, f, what);
}

// fn(f, src, simd, ref, what) for every SIMD target the CPU runs, every packed kind f and every
// pad: a w x h random source (seed) for each; what names the target and the kind.
template <class Fn>
void for_every_target_and_kind(int w, int h, std::initializer_list<int> pads, unsigned seed, Fn fn) {
  for_every_target([&](std::int64_t target) {
    for (const Kind& f : kPacked)
      for (int pad : pads) {
        const Source src = random_source(w, h, f, pad, seed);
        fn(f, src.view, dispatched_samplers(f.kind), scalar_samplers(f.kind), target_name(target) + " " + f.name);
      }
  });
}

}  // namespace

// segment_within, the kernels' test once per segment that its blocks need no checks, against
// every sample's taps as tap() rounds them, one by one (and no segment of no samples).
TEST(SegmentWithin, HoldsWhenEverySampleTapLiesInsideTheBounds) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(0, 1);
  int inside = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const int n = trial % 41, last_x = 20 + trial % 7, last_y = 5 + trial % 3;
    const std::int32_t sx_end = 65536 + trial % 5 * 10000;
    Affine a{fixed(34 * u(rng) - 4), fixed(10 * u(rng) - 2), fixed(2.4 * u(rng) - 0.2), fixed(0.3 * (u(rng) - 0.5))};
    if (trial % 2) {  // on the edges, to the unit: a tap's rounding (m - 1/512 px), the slopes' limits
      const int d = static_cast<int>(rng() % 5) - 2;
      auto edge = [&](std::int32_t v) { return (v + 128) / 65536 * 65536 - 128 + d; };
      a.ax = edge(a.ax), a.ay = edge(a.ay);
      if (trial % 3 == 0) a.sy = (a.sy < 0 ? -8192 : 8192) + d;
      if (trial % 5 == 0) a.sx = sx_end + d;
    }
    bool want = n >= 1 && a.sx >= 0 && a.sx < sx_end && std::abs(a.sy) < 8192;  // |sy| below 1/8 row
    for (int k = 0; k < n && want; ++k) {
      const Tap t = tap(a.ax + k * a.sx, a.ay + k * a.sy);
      want = t.x0 >= 0 && t.x0 <= last_x && t.y0 >= 0 && t.y0 <= last_y;
    }
    ASSERT_EQ(segment_within(a, n, sx_end, last_x, last_y), want)
        << "trial " << trial << ": n " << n << " a " << a.ax << " " << a.ay << " " << a.sx << " " << a.sy;
    inside += want;
  }
  EXPECT_GT(inside, 1000);  // both answers are common
}

TEST(SimdTargets, TheBestCompiledTargetIsTheOneUsed) {
  const std::vector<std::int64_t> targets = simd_targets();
  ASSERT_FALSE(targets.empty());
  EXPECT_EQ(simd_target_name(), target_name(targets.front()));
  for (std::int64_t t : targets) std::printf("SIMD target: %s\n", target_name(t).c_str());
#if defined(__aarch64__)
  bool neon = false;
  for (std::int64_t t : targets) neon |= target_name(t) == "NEON";
  EXPECT_TRUE(neon) << "arm64 always has NEON";
#endif
}

TEST_F(EveryTarget, RowPositionsEqualTheScalarReference) {
  for_every_target_and_kind(61, 23, {0, 5}, 3, [](const Kind& f, const SamplePlane& src, const Samplers& simd, const Samplers& ref,
                                                  const std::string& what) {
    std::mt19937 rng(17);
    for (int trial = 0; trial < 400; ++trial) {
      const int n = trial % 53;
      const Positions p = random_positions(rng, n, src.width, src.height);
      std::vector<std::uint8_t> a = guarded(n, f), b = guarded(n, f);
      simd.row(src, p.xs.data(), p.ys.data(), a.data(), n);
      ref.row(src, p.xs.data(), p.ys.data(), b.data(), n);
      expect_same(a, b, n, f, what + " row trial " + std::to_string(trial));
    }
  });
}

TEST_F(EveryTarget, AffineSegmentsEqualTheScalarReference) {
  for_every_target_and_kind(77, 31, {0, 3}, 5, [](const Kind& f, const SamplePlane& src, const Samplers& simd, const Samplers& ref,
                                                  const std::string& what) {
    std::mt19937 rng(23);
    for (int trial = 0; trial < 600; ++trial) {
      const int n = trial % 71;
      const Affine a = random_affine(rng, src.width, src.height);
      expect_segment_same(simd, ref, src, a, n, f, what + " affine trial " + std::to_string(trial));
    }
  });
}

// Segments from inside the image at every magnification from 0.5 to 2.5 and slopes up to a
// tenth of a row a pixel: the limits of the windows (2 px a pixel for Mono8's and the U V pairs',
// 4/3 for RGB24's blocks of eight) are crossed in small steps, so a fit bound set beyond its
// window's limit shows as a wrong byte.
TEST_F(EveryTarget, SegmentsAtEveryMagnificationEqualTheScalarReference) {
  for_every_target_and_kind(300, 40, {1}, 11, [](const Kind& f, const SamplePlane& src, const Samplers& simd, const Samplers& ref,
                                                 const std::string& what) {
    std::mt19937 rng(31);
    std::uniform_real_distribution<double> u(0, 1);
    for (int trial = 0; trial < 600; ++trial) {
      const double sx = 0.5 + 2.0 * trial / 600.0, sy = 0.2 * (u(rng) - 0.5);
      const int n = 64 + trial % 65;
      const Affine a{fixed(1 + 10 * u(rng)), fixed(12 + 16 * u(rng)), fixed(sx), fixed(sy)};
      expect_segment_same(simd, ref, src, a, n, f, what + " sx " + std::to_string(sx) + " trial " + std::to_string(trial));
    }
  });
}

// Segments at the limits of what the windows hold (AVX-512 VBMI's steps of 32 samples through
// 128 bytes: 31 sx <= 62 px for U V pairs, 40 px for RGB24, 126 px for Mono8; 31 |sy| < 1 row;
// the window ending at the row's end; top taps down to the last row but one): slopes either
// side of each limit, and segments whose first steps fit and whose later ones leave the window
// (the right edge, the bottom rows).
TEST_F(EveryTarget, SegmentsAtTheWindowLimitsEqualTheScalarReference) {
  for_every_target_and_kind(200, 24, {0}, 13, [](const Kind& f, const SamplePlane& src, const Samplers& simd, const Samplers& ref,
                                                 const std::string& what) {
    std::mt19937 rng(37);
    std::uniform_real_distribution<double> u(0, 1);
    for (int trial = 0; trial < 1600; ++trial) {
      // around 62 / 31 = 2 px, 40 / 31 = 1.29 px, 126 / 31 = 4.06 px; near 1 px at the right edge
      const int family = trial % 4;
      const double sx = family == 0   ? 1.95 + 0.1 * u(rng)
                        : family == 1 ? 1.25 + 0.08 * u(rng)
                        : family == 2 ? 3.95 + 0.2 * u(rng)
                                      : 0.95 + 0.1 * u(rng);
      const double sy = (trial % 4 < 2 ? 1 : -1) * 0.036 * u(rng);  // either side of 1 / 31 = 0.0323
      const int n = 96;
      const double x = family < 3 ? 12 * u(rng) : src.width - n * sx - 20 + 40 * u(rng), y = (src.height + 1) * u(rng) - 1;
      const Affine a{fixed(x), fixed(y), fixed(sx), fixed(sy)};
      expect_segment_same(simd, ref, src, a, n, f, what + " trial " + std::to_string(trial));
    }
  });
}

// A run of cells in one call is its cells one after the other: each kernel against the
// scalar reference, and the reference against its cells sampled one call each.
TEST_F(EveryTarget, RunsOfCellsAreTheirSegmentsInTurn) {
  for_every_target_and_kind(90, 40, {2}, 7, [](const Kind& f, const SamplePlane& src, const Samplers& simd, const Samplers& ref,
                                               const std::string& kind) {
    std::mt19937 rng(29);
    for (int trial = 0; trial < 120; ++trial) {
      const int cell_n = 8 << (trial % 3), cells = 1 + trial % 5;
      const int total = cells * cell_n - (trial % 4 == 0 ? cell_n / 2 + 1 : 0);  // a short last cell
      std::vector<Affine> a(cells);
      for (Affine& c : a) c = random_affine(rng, src.width, src.height);
      std::vector<std::uint8_t> got = guarded(total, f), want = guarded(total, f), one_by_one = guarded(total, f);
      simd.cells(src, a.data(), cell_n, total, got.data());
      ref.cells(src, a.data(), cell_n, total, want.data());
      for (int k = 0; k * cell_n < total; ++k)
        affine(ref, src, a[k], one_by_one.data() + k * cell_n * f.pixel_bytes(), std::min(cell_n, total - k * cell_n));
      const std::string what = kind + " run trial " + std::to_string(trial);
      expect_same(got, want, total, f, what);
      expect_same(want, one_by_one, total, f, what + " (reference, cell by cell)");
    }
  });
}

TEST_F(EveryTarget, ATranslationInsideTheImageIsTheBilinearBlend) {
  // Independent of the reference: a Mono8 ramp 3x + 5y sampled at (x + 0.25, 3.5). Rows 3 and
  // 4 blend to (768 x + 4160) >> 8 = 3x + 16 and (768 x + 5440) >> 8 = 3x + 21, then
  // (3x + 16 + 3x + 21 + 1) >> 1 = 3x + 19 (exact: 3x + 18.25; one rounding per direction).
  for_every_target([](std::int64_t target) {
    Source src = random_source(64, 16, kPacked[0], 0, 1);
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 64; ++x) src.bytes[y * 64 + x] = static_cast<std::uint8_t>(3 * x + 5 * y);
    const Samplers k = dispatched_samplers(SampleKind::U8);
    std::vector<std::uint8_t> out(32);
    affine(k, src.view, {fixed(2.25), fixed(3.5), fixed(1), 0}, out.data(), 32);
    for (int i = 0; i < 32; ++i) EXPECT_EQ(out[i], 3 * (2 + i) + 19) << target_name(target) << " pixel " << i;
  });
}

TEST_F(EveryTarget, ChromaOutsideThePlaneIsNeutralGrey) {
  // U V pairs read 128 outside the plane (so that a border does not turn green): all four taps
  // outside (the SIMD kernels' zero path), and half outside (blended with 128).
  for_every_target([](std::int64_t target) {
    Source src = random_source(40, 12, kPacked[1], 0, 9);
    std::fill(src.bytes.begin(), src.bytes.end(), std::uint8_t{200});
    const Samplers k = dispatched_samplers(SampleKind::U8x2);
    std::vector<std::uint8_t> out(2 * 16);
    affine(k, src.view, {fixed(-100), fixed(3), fixed(1), 0}, out.data(), 16);
    for (int i = 0; i < 32; ++i) EXPECT_EQ(out[i], 128) << target_name(target) << " byte " << i;
    affine(k, src.view, {fixed(-0.5), fixed(3), 0, 0}, out.data(), 16);  // halfway between fill and 200
    for (int i = 0; i < 32; ++i) EXPECT_EQ(out[i], 164) << target_name(target) << " byte " << i;
  });
}

// A strided plane (a Bayer site: every other sample of every other row, starting at byte 0 or
// 1 of its pair; YUYV's luma; YUYV's U V: two channels two bytes apart, four bytes per pair;
// one byte in three, the generic strided kind)
// gives the values the packed plane holding the same samples gives, written at the strided
// places and nowhere else, on every SIMD target. The source's last row ends with the plane's
// last sample and the output with its last byte (the sanitizer tree catches any access beyond).
TEST_F(EveryTarget, StridedPlanesSampleLikeThePackedPlaneOfTheirSamples) {
  struct Case {
    const Kind& packed;
    int step, channel_step, offset;
    SampleKind strided;
  };
  const Case cases[] = {{kPacked[0], 2, 1, 0, SampleKind::StridedU8x2},
                        {kPacked[0], 2, 1, 1, SampleKind::StridedU8x2},
                        {kPacked[3], 4, 2, 0, SampleKind::StridedU16},
                        {kPacked[3], 4, 2, 2, SampleKind::StridedU16},
                        {kPacked[1], 4, 2, 1, SampleKind::StridedUV4},
                        {kPacked[0], 3, 1, 0, SampleKind::StridedU8}};
  for_every_target([&](std::int64_t target) {
    for (const Case& c : cases) {
      const int w = 61, h = 15, b = c.packed.bytes, ch = c.packed.channels;
      const Source packed = random_source(w, h, c.packed, 0, 11);
      const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(w) * c.step, stride = 2 * row;  // every other row
      std::vector<std::uint8_t> mosaic(static_cast<std::size_t>(stride * (h - 1) + row - (c.step - c.offset - (ch - 1) * c.channel_step - b)), 0x5A);
      SamplePlane strided = packed.view;
      strided.data = mosaic.data() + c.offset, strided.stride = stride;
      strided.step = c.step, strided.channel_step = c.channel_step;
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          for (int k = 0; k < ch; ++k)
            std::memcpy(strided.row(y) + x * c.step + k * c.channel_step, packed.view.row(y) + (x * ch + k) * b, b);
      ASSERT_EQ(sample_kind(strided), c.strided);
      const Samplers ref = scalar_samplers(c.packed.kind), simd = dispatched_samplers(c.strided);
      const std::string what = target_name(target) + " " + c.packed.name + " step " + std::to_string(c.step) + " offset " +
                               std::to_string(c.offset);
      std::mt19937 rng(29);
      for (int trial = 0; trial < 400; ++trial) {
        const int n = 1 + trial % 71;
        const bool per_pixel = trial % 2;
        const Affine a = random_affine(rng, w, h);
        const Positions q = random_positions(rng, n, w, h);
        std::vector<std::uint8_t> want(static_cast<std::size_t>(n) * ch * b), got(static_cast<std::size_t>(n) * c.step, kGuard);
        std::uint8_t* out = got.data() + c.offset;
        if (per_pixel) {
          ref.row(packed.view, q.xs.data(), q.ys.data(), want.data(), n);
          simd.row(strided, q.xs.data(), q.ys.data(), out, n);
        } else if (trial % 4 == 2) {  // a run of cells: the row goes on after each but the last
          const int cell_n = 8 << (trial / 4 % 3);
          std::vector<Affine> run((n + cell_n - 1) / cell_n);
          for (Affine& r : run) r = random_affine(rng, w, h);
          ref.cells(packed.view, run.data(), cell_n, n, want.data());
          simd.cells(strided, run.data(), cell_n, n, out);
        } else {
          affine(ref, packed.view, a, want.data(), n);
          affine(simd, strided, a, out, n);
        }
        for (int i = 0; i < n; ++i)
          for (int k = 0; k < ch; ++k)
            ASSERT_EQ(std::memcmp(out + i * c.step + k * c.channel_step, want.data() + (i * ch + k) * b, b), 0)
                << what << " trial " << trial << " sample " << i;
        for (std::size_t i = 0; i < got.size(); ++i) {  // bytes of the other planes untouched
          const int in_sample = static_cast<int>((i + c.step - c.offset) % c.step);
          bool ours = static_cast<int>(i) >= c.offset;
          bool any = false;
          for (int k = 0; k < ch; ++k) any |= in_sample >= k * c.channel_step && in_sample < k * c.channel_step + b;
          if (!(ours && any)) {
            ASSERT_EQ(got[i], kGuard) << what << " byte " << i;
          }
        }
      }
    }
  });
}
