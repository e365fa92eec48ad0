// A view split into its planes, two ways:
// - memory planes: the runs of rows a copy must move (one for packed formats and YUYV and
//   the mosaics, two for NV12, three for I420);
// - sample planes: the grids of samples that bilinear resampling treats as one image each, so
//   that nothing is ever interpolated across different kinds of sample: the luma and the
//   chroma of YUV (chroma at half resolution, U and V as two interleaved channels), and a
//   Bayer mosaic's four colour sites (each a half-resolution grid, so no colour bleeds into
//   another's site).
#pragma once

#include <cstddef>
#include <cstdint>

#include "dsp/core/image.hpp"

namespace rsd::dsp {

struct MemoryPlane {
  std::uint8_t* data = nullptr;
  std::size_t row_bytes = 0;
  int rows = 0;
  std::ptrdiff_t stride = 0;
};

// At most three; returns how many.
int memory_planes(const ImageView& v, MemoryPlane out[3]);

// Copies every plane of src into dst (same size and format; strides may differ).
void copy_image(const ImageView& src, const ImageView& dst);
// The same from a buffer laid out in dst's format with rows `src_stride` bytes apart (a
// driver's buffer, a message's bytes): read only.
void copy_image(const std::uint8_t* src, std::ptrdiff_t src_stride, const ImageView& dst);

struct SamplePlane {
  std::uint8_t* data = nullptr;   // sample (0, 0)
  int width = 0, height = 0;      // in samples
  std::ptrdiff_t stride = 0;      // bytes between sample rows
  int step = 1;                   // bytes between neighbouring samples of a row
  int channels = 1;               // interleaved channels of a sample (U and V: 2)
  int channel_step = 1;           // bytes between them
  int sample_bytes = 1;           // 1, or 2 (little-endian)
  std::uint16_t fill = 0;         // what lies outside the image: black, or neutral chroma
  // Image pixels per sample, and the image position of sample (0, 0): sample (i, j) sits at
  // (scale_x i + offset_x, scale_y j + offset_y) in image pixels.
  int scale_x = 1, scale_y = 1;
  double offset_x = 0, offset_y = 0;

  std::uint8_t* row(int y) const { return data + y * stride; }
  // Samples of each channel one after the other, as Mono8, Mono16 and RGB24 are.
  bool packed() const { return step == channels * sample_bytes && channel_step == sample_bytes; }
};

// At most four; returns how many.
int sample_planes(const ImageView& v, SamplePlane out[4]);

// n samples of plane p from `at` (a sample's first byte) set to the plane's fill: black, or
// neutral chroma. The bytes between them (other planes') are left alone.
void fill_samples(const SamplePlane& p, std::uint8_t* at, int n);

}  // namespace rsd::dsp
