#include "dsp/core/pixel_conversion.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "dsp/core/image_planes.hpp"

namespace rsd::dsp {

namespace {

std::uint8_t clamp8(double v) { return static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L)); }

struct Yuv {
  double y, u, v;
};

Yuv yuv(const std::uint8_t* p) {
  const double r = p[0], g = p[1], b = p[2];
  return {0.299 * r + 0.587 * g + 0.114 * b, 128 - 0.168736 * r - 0.331264 * g + 0.5 * b,
          128 + 0.5 * r - 0.418688 * g - 0.081312 * b};
}

void rgb_of(double y, double u, double v, std::uint8_t* out) {
  out[0] = clamp8(y + 1.402 * (v - 128));
  out[1] = clamp8(y - 0.344136 * (u - 128) - 0.714136 * (v - 128));
  out[2] = clamp8(y + 1.772 * (u - 128));
}

const std::uint8_t* px(const ImageView& rgb, int x, int y) {
  x = std::clamp(x, 0, rgb.width - 1), y = std::clamp(y, 0, rgb.height - 1);
  return rgb.row(y) + 3 * x;
}

void store_sample(std::uint8_t* p, int bytes, std::uint8_t v) {
  p[0] = v;
  if (bytes == 2) p[1] = v;  // v * 257, little-endian
}

std::uint8_t load_sample(const std::uint8_t* p, int bytes) { return bytes == 2 ? p[1] : p[0]; }

void check(const ImageView& rgb, const ImageView& other) {
  if (rgb.format != PixelFormat::Rgb8 || rgb.width != other.width || rgb.height != other.height)
    throw std::invalid_argument("pixel conversion: needs an rgb8 image of the other image's size");
  if (std::string why; !size_fits(other.format, other.width, other.height, &why))
    throw std::invalid_argument("pixel conversion: " + why);
}

// The chroma sample (i, j) of a plane: the mean over the pixels it stands for.
Yuv chroma_at(const ImageView& rgb, const SamplePlane& c, int i, int j) {
  Yuv s{0, 0, 0};
  if (c.scale_y == 2) {  // 4:2:0, centred in its 2x2 cell
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const Yuv q = yuv(px(rgb, 2 * i + dx, 2 * j + dy));
        s.u += 0.25 * q.u, s.v += 0.25 * q.v;
      }
    return s;
  }
  const double w[3] = {0.25, 0.5, 0.25};  // 4:2:2, on the even pixel
  for (int d = -1; d <= 1; ++d) {
    const Yuv q = yuv(px(rgb, 2 * i + d, j));
    s.u += w[d + 1] * q.u, s.v += w[d + 1] * q.v;
  }
  return s;
}

void yuv_from_rgb(const ImageView& rgb, const ImageView& dst) {
  SamplePlane p[4];
  const int n = sample_planes(dst, p);
  for (int y = 0; y < dst.height; ++y)
    for (int x = 0; x < dst.width; ++x) p[0].row(y)[x * p[0].step] = clamp8(yuv(px(rgb, x, y)).y);
  for (int j = 0; j < p[1].height; ++j)
    for (int i = 0; i < p[1].width; ++i) {
      const Yuv c = chroma_at(rgb, p[1], i, j);
      if (n == 3) {  // I420: U and V planes
        p[1].row(j)[i] = clamp8(c.u), p[2].row(j)[i] = clamp8(c.v);
      } else {
        std::uint8_t* q = p[1].row(j) + i * p[1].step;
        q[0] = clamp8(c.u), q[p[1].channel_step] = clamp8(c.v);
      }
    }
}

}  // namespace

int bayer_colour(PixelFormat f, int x, int y) {
  // The 2x2 cell's colours in reading order.
  static constexpr int kRggb[4] = {0, 1, 1, 2}, kBggr[4] = {2, 1, 1, 0}, kGrbg[4] = {1, 0, 2, 1}, kGbrg[4] = {1, 2, 0, 1};
  const int k = (y & 1) * 2 + (x & 1);
  switch (f) {
    case PixelFormat::BayerRggb8: case PixelFormat::BayerRggb16: return kRggb[k];
    case PixelFormat::BayerBggr8: case PixelFormat::BayerBggr16: return kBggr[k];
    case PixelFormat::BayerGrbg8: case PixelFormat::BayerGrbg16: return kGrbg[k];
    case PixelFormat::BayerGbrg8: case PixelFormat::BayerGbrg16: return kGbrg[k];
    default: throw std::invalid_argument("bayer_colour: not a Bayer format");
  }
}

void convert_from_rgb(const ImageView& rgb, const ImageView& dst) {
  check(rgb, dst);
  const PixelFormat f = dst.format;
  if (f == PixelFormat::Rgb8) return copy_image(rgb, dst);
  if (is_yuv(f)) return yuv_from_rgb(rgb, dst);
  const int b = sample_bytes(f);
  for (int y = 0; y < dst.height; ++y)
    for (int x = 0; x < dst.width; ++x) {
      const std::uint8_t* p = px(rgb, x, y);
      const std::uint8_t v = is_bayer(f) ? p[bayer_colour(f, x, y)] : clamp8(yuv(p).y);
      store_sample(dst.row(y) + x * b, b, v);
    }
}

void convert_to_rgb(const ImageView& src, const ImageView& rgb) {
  check(rgb, src);
  const PixelFormat f = src.format;
  if (f == PixelFormat::Rgb8) return copy_image(src, rgb);
  SamplePlane p[4];
  const int n = sample_planes(src, p);
  for (int y = 0; y < src.height; ++y)
    for (int x = 0; x < src.width; ++x) {
      std::uint8_t* out = rgb.row(y) + 3 * x;
      if (is_yuv(f)) {
        const int i = x / 2, j = p[1].scale_y == 2 ? y / 2 : y;
        const std::uint8_t* c = p[1].row(j) + i * p[1].step;
        const double u = c[0], v = n == 3 ? p[2].row(j)[i] : c[p[1].channel_step];
        rgb_of(p[0].row(y)[x * p[0].step], u, v, out);
      } else if (is_bayer(f)) {
        const int b = sample_bytes(f);
        double sum[3] = {0, 0, 0}, count[3] = {0, 0, 0};
        const int own = bayer_colour(f, x, y);
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int sx = x + dx, sy = y + dy;
            if (sx < 0 || sy < 0 || sx >= src.width || sy >= src.height) continue;
            const int c = bayer_colour(f, sx, sy);
            if (c != own || (dx == 0 && dy == 0)) sum[c] += load_sample(src.row(sy) + sx * b, b), count[c] += 1;
          }
        for (int c = 0; c < 3; ++c) out[c] = clamp8(sum[c] / std::max(count[c], 1.0));
      } else {
        const std::uint8_t g = load_sample(src.row(y) + x * sample_bytes(f), sample_bytes(f));
        out[0] = out[1] = out[2] = g;
      }
    }
}

namespace {

// (R + 2 G + B) / 4 of the 2x2 mosaic cell whose top-left site is (x, y), 8-bit.
std::uint8_t cell_luma(const ImageView& src, int x, int y, int bytes) {
  int sum = 0;  // one red, two green and one blue site
  for (int dy = 0; dy < 2; ++dy)
    for (int dx = 0; dx < 2; ++dx) sum += load_sample(src.row(y + dy) + bytes * (x + dx), bytes);
  return static_cast<std::uint8_t>((sum + 2) >> 2);
}

}  // namespace

void convert_to_luma(const ImageView& src, const ImageView& mono8) {
  if (mono8.format != PixelFormat::Mono8 || mono8.width != src.width || mono8.height != src.height)
    throw std::invalid_argument("pixel conversion: luma needs a mono8 image of the source's size");
  const int w = src.width, bytes = sample_bytes(src.format);
  for (int y = 0; y < src.height; ++y) {
    const std::uint8_t* in = src.row(y);
    std::uint8_t* out = mono8.row(y);
    switch (src.format) {
      case PixelFormat::Mono8:
      case PixelFormat::Nv12:
      case PixelFormat::I420: std::memcpy(out, in, static_cast<size_t>(w)); break;  // Y is the first plane
      case PixelFormat::Mono16:
        for (int x = 0; x < w; ++x) out[x] = in[2 * x + 1];
        break;
      case PixelFormat::Yuyv:
        for (int x = 0; x < w; ++x) out[x] = in[2 * x];
        break;
      case PixelFormat::Rgb8:
        for (int x = 0; x < w; ++x) out[x] = static_cast<std::uint8_t>((77 * in[3 * x] + 150 * in[3 * x + 1] + 29 * in[3 * x + 2] + 128) >> 8);
        break;
      default:  // a mosaic: even sizes (size_fits), so every cell is whole
        for (int x = 0; x < w; x += 2) out[x] = out[x + 1] = cell_luma(src, x, y & ~1, bytes);
    }
  }
}

}  // namespace rsd::dsp
