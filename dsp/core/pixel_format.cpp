#include "dsp/core/pixel_format.hpp"

#include <array>
#include <utility>

namespace rsd::dsp {

namespace {

constexpr std::array<std::pair<PixelFormat, const char*>, 14> kNames{{
    {PixelFormat::Mono8, "mono8"},
    {PixelFormat::Mono16, "mono16"},
    {PixelFormat::Rgb8, "rgb8"},
    {PixelFormat::Yuyv, "yuyv"},
    {PixelFormat::Nv12, "nv12"},
    {PixelFormat::I420, "i420"},
    {PixelFormat::BayerRggb8, "bayer_rggb8"},
    {PixelFormat::BayerBggr8, "bayer_bggr8"},
    {PixelFormat::BayerGrbg8, "bayer_grbg8"},
    {PixelFormat::BayerGbrg8, "bayer_gbrg8"},
    {PixelFormat::BayerRggb16, "bayer_rggb16"},
    {PixelFormat::BayerBggr16, "bayer_bggr16"},
    {PixelFormat::BayerGrbg16, "bayer_grbg16"},
    {PixelFormat::BayerGbrg16, "bayer_gbrg16"},
}};

bool subsampled_420(PixelFormat f) { return f == PixelFormat::Nv12 || f == PixelFormat::I420; }

}  // namespace

const char* format_name(PixelFormat f) {
  for (const auto& [format, name] : kNames)
    if (format == f) return name;
  return "unknown";
}

std::optional<PixelFormat> parse_format_name(std::string_view name) {
  for (const auto& [format, n] : kNames)
    if (name == n) return format;
  return std::nullopt;
}

std::string format_names() {
  std::string s;
  for (const auto& [format, name] : kNames) s += (s.empty() ? "" : ", ") + std::string(name);
  return s;
}

std::size_t row_bytes(PixelFormat f, int width) {
  const std::size_t w = static_cast<std::size_t>(width);
  if (f == PixelFormat::Yuyv) return 2 * w;
  return w * static_cast<std::size_t>(channels(f) * sample_bytes(f));
}

int buffer_rows(PixelFormat f, int height) { return subsampled_420(f) ? height + height / 2 : height; }

std::size_t buffer_bytes(PixelFormat f, int width, int height, std::size_t stride) {
  const std::size_t h = static_cast<std::size_t>(height), w = static_cast<std::size_t>(width);
  if (f == PixelFormat::I420) return h * stride + (h / 2) * (stride / 2) + (h / 2 - 1) * (stride / 2) + w / 2;
  return (static_cast<std::size_t>(buffer_rows(f, height)) - 1) * stride + row_bytes(f, width);
}

std::size_t frame_bytes(PixelFormat f, int width, int height) {
  return row_bytes(f, width) * static_cast<std::size_t>(buffer_rows(f, height));
}

bool size_fits(PixelFormat f, int width, int height, std::string* why) {
  if (width <= 0 || height <= 0) {
    if (why) *why = "image size " + std::to_string(width) + "x" + std::to_string(height) + " is not positive";
    return false;
  }
  const bool even_w = width % 2 == 0, even_h = height % 2 == 0;
  const bool ok = (!is_yuv(f) || even_w) && (!(subsampled_420(f) || is_bayer(f)) || (even_w && even_h));
  if (!ok && why)
    *why = std::string(format_name(f)) + " needs an even " + (is_yuv(f) && f == PixelFormat::Yuyv ? "width" : "width and height") +
           ", not " + std::to_string(width) + "x" + std::to_string(height);
  return ok;
}

}  // namespace rsd::dsp
