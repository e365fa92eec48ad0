// The simulator's textures, against references written independently of them: a picture is the
// bilinear blend of its pixels (white outside), computed here from the bytes; value noise is the
// same at a point whichever points were sampled before it (its per-octave cells are a cache).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "dsp/sim/scene.hpp"

using namespace rsd::dsp;

namespace {

// The picture's intensity at (s, t) from its bytes: the four pixel centres around the point,
// each weighted by the area of the opposite rectangle, a pixel outside the picture white.
Eigen::Vector3d reference_bilinear(const Image& img, double ppm, double s, double t) {
  const double x = s * ppm - 0.5, y = t * ppm - 0.5;
  const double x0 = std::floor(x), y0 = std::floor(y), a = x - x0, b = y - y0;
  auto pixel = [&](double px, double py) -> Eigen::Vector3d {
    if (px < 0 || py < 0 || px >= img.width || py >= img.height) return Eigen::Vector3d::Ones();
    const std::uint8_t* p = img.data.data() + static_cast<size_t>(py) * img.stride() + static_cast<size_t>(px) * 3;
    return Eigen::Vector3d(p[0], p[1], p[2]) / 255.0;
  };
  return (1 - a) * (1 - b) * pixel(x0, y0) + a * (1 - b) * pixel(x0 + 1, y0) + (1 - a) * b * pixel(x0, y0 + 1) +
         a * b * pixel(x0 + 1, y0 + 1);
}

}  // namespace

// Inside, on the last row and column (where two of the four pixels are outside) and beyond.
TEST(BitmapTexture, IsTheBilinearBlendOfItsPixelsWhiteOutside) {
  const int w = 7, h = 5;
  const double ppm = 100;  // 1 cm pixels
  Image img(w, h, PixelFormat::Rgb8);
  std::mt19937 rng(3);
  for (auto& b : img.data) b = static_cast<std::uint8_t>(rng());
  const BitmapTexture tex(img, ppm);
  std::uniform_real_distribution<double> s_of(-0.02, w / ppm + 0.02), t_of(-0.02, h / ppm + 0.02);
  int inside = 0, edge = 0, outside = 0;
  for (int k = 0; k < 20000; ++k) {
    const double s = s_of(rng), t = t_of(rng);
    const Eigen::Vector3d got = tex.colour(s, t).cast<double>(), want = reference_bilinear(img, ppm, s, t);
    ASSERT_LT((got - want).cwiseAbs().maxCoeff(), 1e-6) << "at s " << s << ", t " << t;
    const double x = s * ppm - 0.5, y = t * ppm - 0.5;
    if (x >= 0 && y >= 0 && x < w - 1 && y < h - 1) ++inside;
    else if (x >= -1 && y >= -1 && x < w && y < h) ++edge;
    else ++outside;
  }
  EXPECT_GT(inside, 4000);  // each kind of point met many times
  EXPECT_GT(edge, 2000);
  EXPECT_GT(outside, 1000);
  EXPECT_EQ(tex.colour(-1, -1), Eigen::Vector3f::Ones());
}

// The noise at a point does not depend on the order of the points asked before it, nor on
// another texture asked in between (each octave keeps the last cell it hashed).
TEST(NoiseTexture, ValuesDoNotDependOnWhatWasSampledBefore) {
  const NoiseTexture a(7, 0.05), b(8, 0.05);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coord(-1, 1);
  std::vector<Eigen::Vector2d> points(2000);
  for (auto& p : points) p = {coord(rng), coord(rng)};
  std::vector<Eigen::Vector3f> forward;
  for (const auto& p : points) forward.push_back(a.colour(p.x(), p.y()));
  int differs_from_b = 0;
  for (size_t i = points.size(); i-- > 0;) {
    const Eigen::Vector3f other = b.colour(points[i].x(), points[i].y());  // the other seed's cells in between
    const Eigen::Vector3f again = a.colour(points[i].x(), points[i].y());
    EXPECT_EQ(again, forward[i]) << i;  // bit for bit
    const NoiseTexture fresh(7, 0.05);
    EXPECT_EQ(fresh.colour(points[i].x(), points[i].y()), forward[i]) << i;
    differs_from_b += (other - again).cwiseAbs().maxCoeff() > 1e-3f;
  }
  EXPECT_GT(differs_from_b, 1900);  // the seeds give different noise: the check is not vacuous
}
