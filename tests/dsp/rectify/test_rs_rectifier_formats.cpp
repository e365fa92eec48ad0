// The native pixel formats (YUYV, NV12, I420, Bayer 8 and 16 bit) through the rectifier, against
// ground truth computed without it:
// - every sample of every plane (luma, chroma at its siting, each mosaic site) is the bilinear
//   blend of its own source plane at the exact source position of the sample's image position
//   (exact_map.hpp), a double-precision blend over the plane's samples;
// - zero motion keeps every byte; a mosaic's colours never mix (a red image keeps green and
//   blue sites at exactly zero); SIMD equals scalar; rectify() allocates nothing;
// - the conversions the simulator uses (RGB to each format and back) on smooth images.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "dsp/core/image_planes.hpp"
#include "dsp/core/pixel_conversion.hpp"
#include "dsp/rectify/rs_rectifier.hpp"
#include "tests/dsp/rectify/exact_map.hpp"
#include "tests/support/allocation_counter.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;
using namespace rsd::dsp::test;

namespace {

const PixelFormat kNative[] = {PixelFormat::Yuyv,        PixelFormat::Nv12,        PixelFormat::I420,
                               PixelFormat::BayerRggb8,  PixelFormat::BayerBggr8,  PixelFormat::BayerGrbg8,
                               PixelFormat::BayerGbrg8,  PixelFormat::BayerRggb16, PixelFormat::BayerBggr16,
                               PixelFormat::BayerGrbg16, PixelFormat::BayerGbrg16};

double sample_at(const SamplePlane& p, int x, int y, int c) {
  const std::uint8_t* q = p.row(y) + x * p.step + c * p.channel_step;
  return p.sample_bytes == 2 ? q[0] + 256.0 * q[1] : q[0];
}

void set_sample(const SamplePlane& p, int x, int y, int c, double v) {
  std::uint8_t* q = p.row(y) + x * p.step + c * p.channel_step;
  const long n = std::lround(v);
  q[0] = static_cast<std::uint8_t>(n & 255);
  if (p.sample_bytes == 2) q[1] = static_cast<std::uint8_t>(n >> 8);
}

// Every plane a smooth function of the image position of its samples (steep enough that a
// half-pixel error in a plane's siting moves values by several levels).
Image smooth_image(int w, int h, PixelFormat f) {
  Image img(w, h, f);
  SamplePlane p[4];
  const int n = sample_planes(img.view(), p);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < p[k].height; ++j)
      for (int i = 0; i < p[k].width; ++i)
        for (int c = 0; c < p[k].channels; ++c) {
          const double X = p[k].scale_x * i + p[k].offset_x, Y = p[k].scale_y * j + p[k].offset_y;
          const double v = 128 + 60 * std::sin(0.15 * X + 0.7 * (k + c)) * std::cos(0.12 * Y - 0.3 * c);
          set_sample(p[k], i, j, c, p[k].sample_bytes == 2 ? 257 * v : v);
        }
  return img;
}

// Double-precision bilinear blend of a plane at (u, v) in its samples; the fill outside.
double bilinear(const SamplePlane& p, double u, double v, int c) {
  const int x0 = static_cast<int>(std::floor(u)), y0 = static_cast<int>(std::floor(v));
  const double fx = u - x0, fy = v - y0;
  auto at = [&](int x, int y) { return x < 0 || y < 0 || x >= p.width || y >= p.height ? p.fill : sample_at(p, x, y, c); };
  return (1 - fy) * ((1 - fx) * at(x0, y0) + fx * at(x0 + 1, y0)) + fy * ((1 - fx) * at(x0, y0 + 1) + fx * at(x0 + 1, y0 + 1));
}

Case small(const Case& c) {
  Case s = c;
  s.cam = camera(160, 120, 60), s.cam.dist = c.cam.dist;
  s.timing = RowTiming::full_frame(120, 30, c.timing.readout);
  s.t_ref = c.t_ref == 0 ? 0 : reference_time(s.timing, ReferenceRow::Middle);
  return s;
}

}  // namespace

// Every other output sample each way is checked against the exact solve (every sixth under a
// sanitizer, where each solve costs ten times as much, every eighth under qemu, where it costs
// thirty times: at every fourth it was 224 s of the arm64 tree's 660 test-seconds, 60 s at
// every eighth, most of it the SVE kernels' emulation). The rectifier still writes every
// sample, so what the sanitizer watches, the sampler's reads and writes, and what the arm64
// tree compares, its kernels' arithmetic on every plane, are unchanged; two hundred samples or
// more a format are still compared.
constexpr int kStride = rsd::test::kEmulated ? 8 : rsd::test::kSanitized ? 6 : 2;

TEST(RsRectifierFormats, EverySampleIsItsPlanesBlendAtTheExactSourcePosition) {
  for (const Case& big : cases()) {
    const Case c = small(big);
    const ScrewMotion motion(c.tw);
    for (PixelFormat f : kNative) {
      Image src = smooth_image(160, 120, f), dst(160, 120, f);
      Rectifier rect(c.cam, c.timing, f);
      rect.rectify(src.view(), dst.view(), c.tw, c.depth, c.t_ref);
      SamplePlane sp[4], dp[4];
      const int n = sample_planes(src.view(), sp);
      sample_planes(dst.view(), dp);
      const double unit = sp[0].sample_bytes == 2 ? 257 : 1;
      long compared = 0;
      double worst = 0;
      for (int k = 0; k < n; ++k)
        for (int j = 0; j < dp[k].height; j += kStride)
          for (int i = 0; i < dp[k].width; i += kStride) {
            const Vector2d P(dp[k].scale_x * i + dp[k].offset_x, dp[k].scale_y * j + dp[k].offset_y);
            const RsProjection e = exact_source(c, motion, P);
            if (!e.ok() || !c.cam.contains(e.pixel, -3.0)) continue;  // black, or the borders' fill
            const double u = (e.pixel.x() - sp[k].offset_x) / sp[k].scale_x, v = (e.pixel.y() - sp[k].offset_y) / sp[k].scale_y;
            for (int ch = 0; ch < sp[k].channels; ++ch) {
              worst = std::max(worst, std::abs(sample_at(dp[k], i, j, ch) - bilinear(sp[k], u, v, ch)) / unit);
              ++compared;
            }
          }
      EXPECT_GT(compared, 160 * 120 / (2 * kStride * kStride)) << c.name << " " << format_name(f);
      EXPECT_LE(worst, 2.0) << c.name << " " << format_name(f);
      std::printf("[ %s %s ] worst %.2f levels over %ld samples\n", c.name, format_name(f), worst, compared);
    }
  }
}

TEST(RsRectifierFormats, ZeroMotionKeepsEveryByte) {
  const CameraModel cam = camera(96, 64, 60);
  const RowTiming timing = RowTiming::full_frame(64, 30);
  for (PixelFormat f : kNative) {
    Image src = smooth_image(96, 64, f), dst(96, 64, f);
    Rectifier rect(cam, timing, f);
    const RectifyReport rep = rect.rectify(src.view(), dst.view(), Twist{}, DepthModel::at_infinity(), 0.0);
    EXPECT_TRUE(rep.rectified) << format_name(f);
    EXPECT_EQ(src.data, dst.data) << format_name(f);
  }
}

TEST(RsRectifierFormats, AMosaicsColoursNeverMix) {
  const Case c = small(cases()[0]);
  Image rgb(160, 120, PixelFormat::Rgb8);
  for (std::size_t i = 0; i < rgb.data.size(); i += 3) rgb.data[i] = 240;  // pure red
  for (PixelFormat f : {PixelFormat::BayerRggb8, PixelFormat::BayerGbrg8, PixelFormat::BayerBggr16}) {
    Image src(160, 120, f), dst(160, 120, f);
    convert_from_rgb(rgb.view(), src.view());
    Rectifier rect(c.cam, c.timing, f);
    rect.rectify(src.view(), dst.view(), c.tw, c.depth, c.t_ref);
    const int b = sample_bytes(f);
    long red_sites = 0, red_full = 0;
    for (int y = 0; y < 120; ++y)
      for (int x = 0; x < 160; ++x) {
        const std::uint8_t* q = dst.view().row(y) + x * b;
        const int v = q[b - 1];  // the high byte of a 16-bit sample (240 * 257 = 0xF0F0)
        if (bayer_colour(f, x, y) != 0) {
          ASSERT_EQ(v, 0) << format_name(f) << " green or blue site " << x << "," << y;
        } else {
          ++red_sites;
          red_full += v == 240;
        }
      }
    EXPECT_GT(red_full, red_sites / 2) << format_name(f) << ": red sites inside the image keep their red";
  }
}

TEST(RsRectifierFormats, SimdEqualsScalarAndNothingIsAllocated) {
  const Case c = small(cases()[3]);  // the ground plane: its horizon crosses cells (kinks)
  for (PixelFormat f : kNative) {
    Image src = smooth_image(160, 120, f), a(160, 120, f), b(160, 120, f);
    RectifierConfig simd, scalar;
    scalar.use_simd = false;
    Rectifier rs(c.cam, c.timing, f, simd), rn(c.cam, c.timing, f, scalar);
    rs.rectify(src.view(), a.view(), c.tw, c.depth, c.t_ref);  // warm
    const ImageView sv = src.view(), av = a.view();
    const std::uint64_t before = g_allocations.load();
    rs.rectify(sv, av, c.tw, c.depth, c.t_ref);
    EXPECT_EQ(g_allocations.load() - before, 0u) << format_name(f);
    rn.rectify(src.view(), b.view(), c.tw, c.depth, c.t_ref);
    EXPECT_EQ(a.data, b.data) << format_name(f);
  }
}

// A smooth 64x48 RGB image: 128 + a sin(kx x + channel) cos(ky y) in every channel.
Image smooth_rgb(double a, double kx, double ky) {
  Image rgb(64, 48, PixelFormat::Rgb8);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x)
      for (int c = 0; c < 3; ++c)
        rgb.data[(y * 64 + x) * 3 + c] = static_cast<std::uint8_t>(128 + a * std::sin(kx * x + c) * std::cos(ky * y));
  return rgb;
}

TEST(PixelConversion, SmoothImagesSurviveTheRoundTrip) {
  Image rgb = smooth_rgb(50, 0.05, 0.04);
  Image back(64, 48, PixelFormat::Rgb8);
  for (PixelFormat f : kNative) {
    Image mid(64, 48, f);
    convert_from_rgb(rgb.view(), mid.view());
    convert_to_rgb(mid.view(), back.view());
    double worst = 0;
    for (int y = 2; y < 46; ++y)
      for (int x = 2; x < 62; ++x)
        for (int c = 0; c < 3; ++c)
          worst = std::max(worst, std::abs(double(back.data[(y * 64 + x) * 3 + c]) - rgb.data[(y * 64 + x) * 3 + c]));
    EXPECT_LE(worst, 6.0) << format_name(f);
  }
  EXPECT_EQ(bayer_colour(PixelFormat::BayerRggb8, 0, 0), 0);
  EXPECT_EQ(bayer_colour(PixelFormat::BayerRggb8, 1, 1), 2);
  EXPECT_EQ(bayer_colour(PixelFormat::BayerGrbg16, 1, 0), 0);
  EXPECT_EQ(bayer_colour(PixelFormat::BayerGbrg8, 0, 1), 0);
  EXPECT_EQ(bayer_colour(PixelFormat::BayerBggr8, 0, 0), 2);
}

// The luma the online calibration tracks features in, against BT.601 luma of the RGB image
// every format was made from: exact for YUV's own Y, within rounding for RGB and 16 bit; for a
// mosaic (R + 2 G + B) / 4 over its 2x2 cell (a smooth image: within a few levels of the pixel's).
TEST(PixelConversion, LumaOfEveryFormatIsTheRgbImagesLuma) {
  Image rgb = smooth_rgb(60, 0.07, 0.05), luma(64, 48, PixelFormat::Mono8);
  for (PixelFormat f : kNative) {
    Image img(64, 48, f);
    convert_from_rgb(rgb.view(), img.view());
    std::fill(luma.data.begin(), luma.data.end(), 0);
    convert_to_luma(img.view(), luma.view());
    double worst = 0;
    for (int y = 0; y < 48; ++y)
      for (int x = 0; x < 64; ++x) {
        const std::uint8_t* p = &rgb.data[(y * 64 + x) * 3];
        const double want = is_bayer(f) ? (p[0] + 2.0 * p[1] + p[2]) / 4 : 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2];
        worst = std::max(worst, std::abs(luma.data[y * 64 + x] - want));
      }
    EXPECT_LE(worst, is_bayer(f) ? 4.0 : 1.0) << format_name(f);
  }
  Image mono16(4, 2, PixelFormat::Mono16);
  EXPECT_THROW(convert_to_luma(mono16.view(), luma.view()), std::invalid_argument);
}

TEST(PixelFormats, SizesAndNames) {
  EXPECT_EQ(frame_bytes(PixelFormat::Nv12, 640, 480), 640u * 480 * 3 / 2);
  EXPECT_EQ(frame_bytes(PixelFormat::I420, 640, 480), 640u * 480 * 3 / 2);
  EXPECT_EQ(frame_bytes(PixelFormat::Yuyv, 640, 480), 640u * 480 * 2);
  EXPECT_EQ(frame_bytes(PixelFormat::BayerGbrg16, 640, 480), 640u * 480 * 2);
  EXPECT_EQ(buffer_bytes(PixelFormat::I420, 4, 4, 6), 4u * 6 + 2 * 3 + 1 * 3 + 2);
  std::string why;
  EXPECT_FALSE(size_fits(PixelFormat::Nv12, 640, 481, &why));
  EXPECT_NE(why.find("even"), std::string::npos) << why;
  EXPECT_TRUE(size_fits(PixelFormat::Yuyv, 640, 481));
  for (PixelFormat f : kNative) EXPECT_EQ(parse_format_name(format_name(f)), f);
  EXPECT_FALSE(parse_format_name("NV12").has_value());
}
