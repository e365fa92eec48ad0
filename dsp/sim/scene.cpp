#include "dsp/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace rsd::dsp {

Eigen::Vector3f CheckerboardTexture::colour(double s, double t) const {
  const double fs = std::floor(s / sq_), ft = std::floor(t / sq_);
  if (fs < 0 || ft < 0 || fs >= cols_ || ft >= rows_) return Eigen::Vector3f::Ones();
  const bool black = (static_cast<long>(fs) + static_cast<long>(ft)) % 2 == 0;
  return black ? Eigen::Vector3f::Zero() : Eigen::Vector3f::Ones();
}

std::vector<Eigen::Vector2d> CheckerboardTexture::inner_corners() const {
  std::vector<Eigen::Vector2d> c;
  for (int j = 1; j < rows_; ++j)
    for (int i = 1; i < cols_; ++i) c.emplace_back(i * sq_, j * sq_);
  return c;
}

NoiseTexture::NoiseTexture(unsigned seed, double cell_m) : seed_(seed), cell_(cell_m) {}

// Integer hash -> [0, 1): a deterministic lattice of random values, one per channel. The
// channel enters the hash last, by xor (seed << 8 keeps the low byte free), so the three
// channels share the multiplications at each lattice point.
std::uint64_t NoiseTexture::lattice_key(long i, long j) const {
  return static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull ^
         (static_cast<std::uint64_t>(j) + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full ^ static_cast<std::uint64_t>(seed_) << 8;
}

float NoiseTexture::lattice(std::uint64_t key, int channel) {
  std::uint64_t h = key ^ static_cast<unsigned>(channel);
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDull;
  h ^= h >> 33;
  return static_cast<float>(h >> 40) / static_cast<float>(1ull << 24);
}

namespace {
// std::floor, without the library call x86-64's baseline instruction set needs for it: exact
// for every |x| below 2^62 (plane coordinates in lattice units are far below).
long floor_to_long(double x) {
  const long i = static_cast<long>(x);
  return x < static_cast<double>(i) ? i - 1 : i;
}
}  // namespace

// One octave of value noise at (s, t) in lattice units, for every channel at once: the cell and
// its smoothstep weights are the channels' common part.
void NoiseTexture::octave(double s, double t, float v[3]) const {
  const long i = floor_to_long(s), j = floor_to_long(t);
  const double a = s - static_cast<double>(i), b = t - static_cast<double>(j);
  // smoothstep weights: continuous gradient, so features are corners rather than seams
  const double wa = a * a * (3 - 2 * a), wb = b * b * (3 - 2 * b);
  const std::uint64_t k00 = lattice_key(i, j), k10 = lattice_key(i + 1, j), k01 = lattice_key(i, j + 1),
                      k11 = lattice_key(i + 1, j + 1);
  for (int ch = 0; ch < 3; ++ch)
    v[ch] = static_cast<float>((1 - wa) * (1 - wb) * lattice(k00, ch) + wa * (1 - wb) * lattice(k10, ch) +
                               (1 - wa) * wb * lattice(k01, ch) + wa * wb * lattice(k11, ch));
}

Eigen::Vector3f NoiseTexture::colour(double s, double t) const {
  float v[3] = {0, 0, 0}, amp = 0.5f, sum = 0;
  double scale = 1.0 / cell_;
  for (int o = 0; o < 4; ++o, amp *= 0.5f, scale *= 2.0) {
    float ov[3];
    octave(s * scale, t * scale, ov);
    for (int ch = 0; ch < 3; ++ch) v[ch] += amp * ov[ch];
    sum += amp;
  }
  // stretch contrast: value noise concentrates around 0.5
  Eigen::Vector3f c;
  for (int ch = 0; ch < 3; ++ch) c[ch] = std::clamp(0.5f + 2.2f * (v[ch] / sum - 0.5f), 0.0f, 1.0f);
  return c;
}

Eigen::Vector3f BitmapTexture::texel(int x, int y) const {
  if (x < 0 || y < 0 || x >= img_.width || y >= img_.height) return Eigen::Vector3f::Ones();
  const std::uint8_t* p = img_.data.data() + static_cast<size_t>(y) * img_.stride() + x * channels(img_.format) * sample_bytes(img_.format);
  if (img_.format == PixelFormat::Rgb8) return Eigen::Vector3f(p[0], p[1], p[2]) / 255.0f;
  const float g = img_.format == PixelFormat::Mono16 ? *reinterpret_cast<const std::uint16_t*>(p) / 65535.0f : p[0] / 255.0f;
  return Eigen::Vector3f::Constant(g);
}

Eigen::Vector3f BitmapTexture::colour(double s, double t) const {
  // Pixel centres sit at half-integer multiples of the pixel size.
  const double x = s * ppm_ - 0.5, y = t * ppm_ - 0.5;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float a = static_cast<float>(x - x0), b = static_cast<float>(y - y0);
  return (1 - a) * (1 - b) * texel(x0, y0) + a * (1 - b) * texel(x0 + 1, y0) + (1 - a) * b * texel(x0, y0 + 1) +
         a * b * texel(x0 + 1, y0 + 1);
}

Plane fronto_parallel(const Eigen::Vector3d& origin, std::shared_ptr<const Texture> texture) {
  Plane p;
  p.axis_s = Eigen::Vector3d::UnitX();
  p.axis_t = Eigen::Vector3d::UnitY();
  p.origin = origin;
  p.texture = std::move(texture);
  return p;
}

Plane fronto_parallel_checkerboard(double z, int cols, int rows, double square_m) {
  return fronto_parallel(Eigen::Vector3d(-0.5 * cols * square_m, -0.5 * rows * square_m, z),
                         std::make_shared<CheckerboardTexture>(cols, rows, square_m));
}

}  // namespace rsd::dsp
