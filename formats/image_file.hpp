// Reading and writing frames as PNG (libpng) and PGM files. Errors throw
// std::runtime_error naming the file and what is wrong with it.
#pragma once

#include <string>

#include "dsp/core/image.hpp"

namespace rsd::formats {

// Writes Mono8, Mono16 (big-endian in the file, as PNG requires) or Rgb8.
void write_png(const std::string& path, const dsp::ImageView& img);

// The largest image a reader accepts, checked against the header before anything is
// allocated: a side of 16384 pixels (the largest frame rsd's configuration accepts) and 2^26
// pixels in all (8192 x 8192; 192 MiB as RGB). A header claiming more is an error naming the file.
inline constexpr long kMaxImageSide = 16384;
inline constexpr long long kMaxImagePixels = 1LL << 26;

// Reads PNG (grey, grey+alpha, RGB, RGBA, palette; 8 or 16 bit) or binary PGM (P5, 8 or
// 16 bit). Alpha is dropped; 16-bit data becomes Mono16 (grey) or is scaled to Rgb8.
dsp::Image read_image(const std::string& path);

}  // namespace rsd::formats
