#include "dsp/sim/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

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

// The four lattice values around one cell of one octave, for every channel. Consecutive samples
// of a render mostly fall in the same cell (a cell spans many pixels), so each octave keeps its
// last cell and hashes only when a sample leaves it: the same values, hashed once per cell.
// Kept per thread, as renderers on several threads may share a texture.
struct NoiseTexture::LatticeCell {
  bool valid = false;
  unsigned seed = 0;
  long i = 0, j = 0;
  float v[4][3];
};

// One octave of value noise at (s, t) in lattice units, for every channel at once: the cell and
// its smoothstep weights are the channels' common part.
void NoiseTexture::octave(double s, double t, LatticeCell& cell, float v[3]) const {
  const long i = floor_to_long(s), j = floor_to_long(t);
  const double a = s - static_cast<double>(i), b = t - static_cast<double>(j);
  // smoothstep weights: continuous gradient, so features are corners rather than seams
  const double wa = a * a * (3 - 2 * a), wb = b * b * (3 - 2 * b);
  if (!cell.valid || cell.i != i || cell.j != j || cell.seed != seed_) {
    const std::uint64_t k[4] = {lattice_key(i, j), lattice_key(i + 1, j), lattice_key(i, j + 1), lattice_key(i + 1, j + 1)};
    for (int q = 0; q < 4; ++q)
      for (int ch = 0; ch < 3; ++ch) cell.v[q][ch] = lattice(k[q], ch);
    cell.valid = true, cell.seed = seed_, cell.i = i, cell.j = j;
  }
  for (int ch = 0; ch < 3; ++ch)
    v[ch] = static_cast<float>((1 - wa) * (1 - wb) * cell.v[0][ch] + wa * (1 - wb) * cell.v[1][ch] +
                               (1 - wa) * wb * cell.v[2][ch] + wa * wb * cell.v[3][ch]);
}

Eigen::Vector3f NoiseTexture::colour(double s, double t) const {
  float v[3] = {0, 0, 0}, amp = 0.5f, sum = 0;
  double scale = 1.0 / cell_;
  thread_local LatticeCell cells[kOctaves];
  for (int o = 0; o < kOctaves; ++o, amp *= 0.5f, scale *= 2.0) {
    float ov[3];
    octave(s * scale, t * scale, cells[o], ov);
    for (int ch = 0; ch < 3; ++ch) v[ch] += amp * ov[ch];
    sum += amp;
  }
  // stretch contrast: value noise concentrates around 0.5
  Eigen::Vector3f c;
  for (int ch = 0; ch < 3; ++ch) c[ch] = std::clamp(0.5f + 2.2f * (v[ch] / sum - 0.5f), 0.0f, 1.0f);
  return c;
}

namespace {

// A byte's intensity, as texel() computes it (b / 255.0f): the lookup gives the same floats.
struct ByteUnits {
  float v[256];
  constexpr ByteUnits() : v{} {
    for (int b = 0; b < 256; ++b) v[b] = static_cast<float>(b) / 255.0f;
  }
};
constexpr ByteUnits kByteUnits;

// An RGB pixel's three intensities.
Eigen::Vector3f rgb_units(const std::uint8_t* p) {
  return Eigen::Vector3f(kByteUnits.v[p[0]], kByteUnits.v[p[1]], kByteUnits.v[p[2]]);
}

}  // namespace

Eigen::Vector3f BitmapTexture::texel(int x, int y) const {
  if (x < 0 || y < 0 || x >= img_.width || y >= img_.height) return Eigen::Vector3f::Ones();
  const std::uint8_t* p = img_.data.data() + static_cast<size_t>(y) * img_.stride() + x * channels(img_.format) * sample_bytes(img_.format);
  if (img_.format == PixelFormat::Rgb8) return rgb_units(p);
  const float g = img_.format == PixelFormat::Mono16 ? *reinterpret_cast<const std::uint16_t*>(p) / 65535.0f : kByteUnits.v[p[0]];
  return Eigen::Vector3f::Constant(g);
}

Eigen::Vector3f BitmapTexture::colour(double s, double t) const {
  // Pixel centres sit at half-integer multiples of the pixel size.
  const double x = s * ppm_ - 0.5, y = t * ppm_ - 0.5;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const float a = static_cast<float>(x - x0), b = static_cast<float>(y - y0);
  // Renderers call this for every sample of every pixel (the simulated camera, the tests' truth
  // renders): an RGB picture's four texels inside it are read without a call each.
  if (img_.format == PixelFormat::Rgb8 && x0 >= 0 && y0 >= 0 && x0 + 1 < img_.width && y0 + 1 < img_.height) {
    const size_t stride = img_.stride();
    const std::uint8_t* p = img_.data.data() + static_cast<size_t>(y0) * stride + static_cast<size_t>(x0) * 3;
    return (1 - a) * (1 - b) * rgb_units(p) + a * (1 - b) * rgb_units(p + 3) + (1 - a) * b * rgb_units(p + stride) +
           a * b * rgb_units(p + stride + 3);
  }
  return (1 - a) * (1 - b) * texel(x0, y0) + a * (1 - b) * texel(x0 + 1, y0) + (1 - a) * b * texel(x0, y0 + 1) +
         a * b * texel(x0 + 1, y0 + 1);
}

Eigen::Vector3f colour_along_ray(const Scene& scene, const std::vector<Eigen::Vector3d>& normals,
                                 const Eigen::Vector3d& centre, const Eigen::Matrix3d& R_wc, const Eigen::Vector3d& ray_c) {
  const Eigen::Vector3d d = R_wc * ray_c;
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3f colour = scene.background;
  for (size_t k = 0; k < scene.planes.size(); ++k) {
    const Plane& p = scene.planes[k];
    const Eigen::Vector3d& n = normals[k];
    const double den = n.dot(d);
    if (std::abs(den) < 1e-12) continue;
    const double lambda = n.dot(p.origin - centre) / den;
    if (!(lambda > 0) || lambda >= best) continue;
    const Eigen::Vector3d rel = centre + lambda * d - p.origin;
    const double s = rel.dot(p.axis_s), t = rel.dot(p.axis_t);
    if (s < p.s_min || s > p.s_max || t < p.t_min || t > p.t_max) continue;
    best = lambda;
    colour = p.texture->colour(s, t);
  }
  return colour;
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
