// The SIMD kernels of every instruction set compiled in and run by this CPU (x86-64: SSSE3,
// SSE4, AVX2, AVX-512, EMU128; arm64 under qemu: NEON, SVE, SVE2) against the scalar reference,
// byte for byte: positions per pixel and affine cell segments, near-translations (the window
// paths), scattered positions (gathers), the borders and outside (scalar code, zeros), padded
// rows, every length up to a few steps. Bytes after a row's end must stay untouched, and the
// source has no slack after its last row (the sanitizer tree catches any read beyond it).
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "dsp/rectify/bilinear_sampling.hpp"

using namespace rsd::dsp;
using namespace rsd::dsp::rectify_detail;

namespace {

constexpr std::uint8_t kGuard = 0xAB;

struct Source {
  std::vector<std::uint8_t> bytes;
  ImageView view;
};

// A random image whose rows are `pad` bytes longer than its pixels; the buffer ends with the
// last pixel.
Source random_source(int w, int h, PixelFormat f, int pad, unsigned seed) {
  Source s;
  const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(w) * bytes_per_pixel(f);
  s.bytes.resize(static_cast<std::size_t>((row + pad) * (h - 1) + row));
  std::mt19937 rng(seed);
  for (auto& b : s.bytes) b = static_cast<std::uint8_t>(rng());
  s.view = {s.bytes.data(), w, h, row + pad, f};
  return s;
}

const char* name(PixelFormat f) {
  switch (f) {
    case PixelFormat::Mono8: return "Mono8";
    case PixelFormat::Mono16: return "Mono16";
    case PixelFormat::Rgb8: return "Rgb8";
  }
  return "?";
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

std::vector<std::uint8_t> guarded(int n, PixelFormat f) {
  return std::vector<std::uint8_t>(static_cast<std::size_t>(n) * bytes_per_pixel(f) + 32, kGuard);
}

// Checks `got` against `want` and that the guard bytes after n pixels are intact.
void expect_same(const std::vector<std::uint8_t>& got, const std::vector<std::uint8_t>& want, int n, PixelFormat f,
                 const std::string& what) {
  const std::size_t used = static_cast<std::size_t>(n) * bytes_per_pixel(f);
  for (std::size_t i = 0; i < got.size(); ++i) {
    const std::uint8_t expected = i < used ? want[i] : kGuard;
    if (got[i] != expected) {
      ADD_FAILURE() << what << ": byte " << i << " of " << used << " is " << int(got[i]) << ", want " << int(expected);
      return;
    }
  }
}

class EveryTarget : public ::testing::Test {
 protected:
  void TearDown() override { force_simd_target(0); }
};

}  // namespace

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
  for (std::int64_t target : simd_targets()) {
    force_simd_target(target);
    for (PixelFormat f : {PixelFormat::Mono8, PixelFormat::Mono16, PixelFormat::Rgb8})
      for (int pad : {0, 5}) {
        const Source src = random_source(61, 23, f, pad, 3);
        const Samplers simd = dispatched_samplers(f), ref = scalar_samplers(f);
        std::mt19937 rng(17);
        for (int trial = 0; trial < 400; ++trial) {
          const int n = trial % 53;
          const Positions p = random_positions(rng, n, src.view.width, src.view.height);
          std::vector<std::uint8_t> a = guarded(n, f), b = guarded(n, f);
          simd.row(src.view, p.xs.data(), p.ys.data(), a.data(), n);
          ref.row(src.view, p.xs.data(), p.ys.data(), b.data(), n);
          expect_same(a, b, n, f, target_name(target) + " " + name(f) + " row trial " + std::to_string(trial));
        }
      }
  }
}

TEST_F(EveryTarget, AffineSegmentsEqualTheScalarReference) {
  for (std::int64_t target : simd_targets()) {
    force_simd_target(target);
    for (PixelFormat f : {PixelFormat::Mono8, PixelFormat::Mono16, PixelFormat::Rgb8})
      for (int pad : {0, 3}) {
        const Source src = random_source(77, 31, f, pad, 5);
        const Samplers simd = dispatched_samplers(f), ref = scalar_samplers(f);
        std::mt19937 rng(23);
        for (int trial = 0; trial < 600; ++trial) {
          const int n = trial % 71;
          const Affine a = random_affine(rng, src.view.width, src.view.height);
          std::vector<std::uint8_t> got = guarded(n, f), want = guarded(n, f);
          simd.affine(src.view, a, got.data(), n);
          ref.affine(src.view, a, want.data(), n);
          expect_same(got, want, n, f, target_name(target) + " " + name(f) + " affine trial " + std::to_string(trial));
        }
      }
  }
}

TEST_F(EveryTarget, ATranslationInsideTheImageIsTheBilinearBlend) {
  // Independent of the reference: a Mono8 ramp 3x + 5y sampled at (x + 0.25, 3.5). Rows 3 and
  // 4 blend to (768 x + 4160) >> 8 = 3x + 16 and (768 x + 5440) >> 8 = 3x + 21, then
  // (3x + 16 + 3x + 21 + 1) >> 1 = 3x + 19 (exact: 3x + 18.25; one rounding per direction).
  for (std::int64_t target : simd_targets()) {
    force_simd_target(target);
    Source src = random_source(64, 16, PixelFormat::Mono8, 0, 1);
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 64; ++x) src.bytes[y * 64 + x] = static_cast<std::uint8_t>(3 * x + 5 * y);
    const Samplers k = dispatched_samplers(PixelFormat::Mono8);
    std::vector<std::uint8_t> out(32);
    k.affine(src.view, {fixed(2.25), fixed(3.5), fixed(1), 0}, out.data(), 32);
    for (int i = 0; i < 32; ++i) EXPECT_EQ(out[i], 3 * (2 + i) + 19) << target_name(target) << " pixel " << i;
  }
}
