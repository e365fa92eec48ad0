// Non-owning views of 8-bit and 16-bit images, as the renderer and rectifier use them.
// The memory belongs to the caller (frame slots allocated once at start).
#pragma once

#include <cstddef>
#include <cstdint>

namespace rsd::dsp {

enum class PixelFormat { Mono8, Mono16, Rgb8 };

inline int channels(PixelFormat f) { return f == PixelFormat::Rgb8 ? 3 : 1; }
inline int bytes_per_pixel(PixelFormat f) {
  return f == PixelFormat::Rgb8 ? 3 : (f == PixelFormat::Mono16 ? 2 : 1);
}

struct ImageView {
  std::uint8_t* data = nullptr;
  int width = 0, height = 0;
  std::ptrdiff_t stride = 0;  // bytes between rows
  PixelFormat format = PixelFormat::Mono8;
  std::uint8_t* row(int y) const { return data + y * stride; }
};

}  // namespace rsd::dsp

#include <vector>

namespace rsd::dsp {

// An image that owns its pixels (tightly packed rows). For tools and tests; the daemon's
// hot path works on views of slots it allocated at start.
struct Image {
  int width = 0, height = 0;
  PixelFormat format = PixelFormat::Mono8;
  std::vector<std::uint8_t> data;

  Image() = default;
  Image(int w, int h, PixelFormat f)
      : width(w), height(h), format(f), data(static_cast<size_t>(w) * h * bytes_per_pixel(f)) {}
  std::ptrdiff_t stride() const { return static_cast<std::ptrdiff_t>(width) * bytes_per_pixel(format); }
  ImageView view() { return {data.data(), width, height, stride(), format}; }
};

}  // namespace rsd::dsp
