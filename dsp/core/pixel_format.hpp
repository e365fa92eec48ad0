// The pixel formats rsd carries end to end, as cameras deliver them, and how each lays out in
// memory. Every format is one buffer with one row stride (V4L2's single-planar layouts):
//   Mono8, Mono16 (little-endian), Rgb8 (R, G, B)   one sample plane, packed
//   Yuyv     4:2:2, Y0 U Y1 V: luma at every pixel, one U and V pair per two pixels
//   Nv12     4:2:0, the luma plane, then h/2 rows of interleaved U V pairs at the same stride
//   I420     4:2:0, the luma plane, then h/2 rows of U and h/2 rows of V, each at stride/2
//   Bayer*8, Bayer*16 (little-endian)   a raw colour mosaic; the name gives the colours of the
//            top-left 2x2 cell in reading order (RGGB: red at even rows and even columns)
// Chroma sits between its luma pixels the way V4L2 documents it: 4:2:0 chroma in the middle of
// its 2x2 luma cell, 4:2:2 chroma on the even luma pixel (image_planes.hpp).
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace rsd::dsp {

enum class PixelFormat {
  Mono8, Mono16, Rgb8,
  Yuyv, Nv12, I420,
  BayerRggb8, BayerBggr8, BayerGrbg8, BayerGbrg8,
  BayerRggb16, BayerBggr16, BayerGrbg16, BayerGbrg16,
};

// The configuration name of a format ("mono8", "nv12", "bayer_rggb16", ...) and back.
const char* format_name(PixelFormat f);
std::optional<PixelFormat> parse_format_name(std::string_view name);
// Every format's name, comma separated (for error messages and --help).
std::string format_names();

// Inline: the renderer asks per texel.
inline bool is_bayer(PixelFormat f) { return f >= PixelFormat::BayerRggb8; }
inline bool is_yuv(PixelFormat f) { return f == PixelFormat::Yuyv || f == PixelFormat::Nv12 || f == PixelFormat::I420; }
// Colour samples at a pixel of the first plane (3 for Rgb8, 1 otherwise).
inline int channels(PixelFormat f) { return f == PixelFormat::Rgb8 ? 3 : 1; }
// Bytes of one sample (2 for Mono16 and the 16-bit Bayer formats).
inline int sample_bytes(PixelFormat f) { return f == PixelFormat::Mono16 || f >= PixelFormat::BayerRggb16 ? 2 : 1; }
// Bytes of one row of the first plane, width pixels wide.
std::size_t row_bytes(PixelFormat f, int width);
// Rows of the buffer at stride `stride` (chroma planes included): h, or 3h/2 for 4:2:0.
int buffer_rows(PixelFormat f, int height);
// Bytes from a frame's first byte to its last at this stride (every plane; I420's chroma rows
// are stride / 2 apart).
std::size_t buffer_bytes(PixelFormat f, int width, int height, std::size_t stride);
// Bytes of a tightly packed frame (stride = row_bytes).
std::size_t frame_bytes(PixelFormat f, int width, int height);
// Whether a format can hold an image of this size (subsampled chroma and mosaics need even
// sizes); otherwise `why` says what is wrong.
bool size_fits(PixelFormat f, int width, int height, std::string* why = nullptr);

}  // namespace rsd::dsp
