// Non-owning views of images in any of rsd's pixel formats (pixel_format.hpp), as the
// renderer and rectifier use them. The memory belongs to the caller (frame slots allocated
// once at start). A view is one buffer: the first plane's rows at `stride`, and for 4:2:0
// formats the chroma rows after them (image_planes.hpp splits a view into its planes).
#pragma once

#include <cstddef>
#include <cstdint>

#include "dsp/core/pixel_format.hpp"

namespace rsd::dsp {

struct ImageView {
  std::uint8_t* data = nullptr;
  int width = 0, height = 0;
  std::ptrdiff_t stride = 0;  // bytes between rows of the first plane
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
  Image(int w, int h, PixelFormat f) : width(w), height(h), format(f), data(frame_bytes(f, w, h)) {}
  std::ptrdiff_t stride() const { return static_cast<std::ptrdiff_t>(row_bytes(format, width)); }
  ImageView view() { return {data.data(), width, height, stride(), format}; }
};

}  // namespace rsd::dsp
