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
