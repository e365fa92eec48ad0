#include "dsp/core/image_planes.hpp"

#include <cstring>

namespace rsd::dsp {

int memory_planes(const ImageView& v, MemoryPlane out[3]) {
  out[0] = {v.data, row_bytes(v.format, v.width), v.height, v.stride};
  if (v.format == PixelFormat::Nv12) {
    out[1] = {v.data + v.height * v.stride, static_cast<std::size_t>(v.width), v.height / 2, v.stride};
    return 2;
  }
  if (v.format == PixelFormat::I420) {
    const std::ptrdiff_t s = v.stride / 2;
    std::uint8_t* u = v.data + v.height * v.stride;
    out[1] = {u, static_cast<std::size_t>(v.width / 2), v.height / 2, s};
    out[2] = {u + (v.height / 2) * s, static_cast<std::size_t>(v.width / 2), v.height / 2, s};
    return 3;
  }
  return 1;
}

void copy_image(const ImageView& src, const ImageView& dst) {
  MemoryPlane s[3], d[3];
  const int n = memory_planes(src, s);
  memory_planes(dst, d);
  for (int p = 0; p < n; ++p)
    for (int y = 0; y < s[p].rows; ++y) std::memcpy(d[p].data + y * d[p].stride, s[p].data + y * s[p].stride, s[p].row_bytes);
}

void copy_image(const std::uint8_t* src, std::ptrdiff_t src_stride, const ImageView& dst) {
  // A view is writable by type only: copy_image reads its source.
  copy_image({const_cast<std::uint8_t*>(src), dst.width, dst.height, src_stride, dst.format}, dst);
}

void fill_samples(const SamplePlane& p, std::uint8_t* at, int n) {
  if (p.packed() && (p.fill == 0 || p.sample_bytes == 1))
    return static_cast<void>(std::memset(at, p.fill, static_cast<std::size_t>(n) * p.step));
  for (int k = 0; k < n; ++k)
    for (int c = 0; c < p.channels; ++c) {
      std::uint8_t* q = at + k * p.step + c * p.channel_step;
      q[0] = static_cast<std::uint8_t>(p.fill);
      if (p.sample_bytes == 2) q[1] = static_cast<std::uint8_t>(p.fill >> 8);
    }
}

namespace {

SamplePlane packed(std::uint8_t* data, int w, int h, std::ptrdiff_t stride, int channels, int bytes) {
  SamplePlane p;
  p.data = data, p.width = w, p.height = h, p.stride = stride;
  p.channels = channels, p.sample_bytes = bytes, p.step = channels * bytes, p.channel_step = bytes;
  return p;
}

// Half-resolution chroma: 4:2:0 centred in its 2x2 luma cell, 4:2:2 on the even pixel.
SamplePlane chroma(SamplePlane p, bool vertical_half) {
  p.fill = 128;
  p.scale_x = 2, p.offset_x = vertical_half ? 0.5 : 0.0;
  p.scale_y = vertical_half ? 2 : 1, p.offset_y = vertical_half ? 0.5 : 0.0;
  return p;
}

}  // namespace

int sample_planes(const ImageView& v, SamplePlane out[4]) {
  const int w = v.width, h = v.height;
  switch (v.format) {
    case PixelFormat::Mono8:
    case PixelFormat::Mono16:
    case PixelFormat::Rgb8:
      out[0] = packed(v.data, w, h, v.stride, channels(v.format), sample_bytes(v.format));
      return 1;
    case PixelFormat::Yuyv: {  // Y0 U Y1 V
      out[0] = packed(v.data, w, h, v.stride, 1, 1);
      out[0].step = 2;
      SamplePlane c = packed(v.data + 1, w / 2, h, v.stride, 2, 1);
      c.step = 4, c.channel_step = 2;
      out[1] = chroma(c, false);
      return 2;
    }
    case PixelFormat::Nv12:
      out[0] = packed(v.data, w, h, v.stride, 1, 1);
      out[1] = chroma(packed(v.data + h * v.stride, w / 2, h / 2, v.stride, 2, 1), true);
      return 2;
    case PixelFormat::I420: {
      const std::ptrdiff_t s = v.stride / 2;
      std::uint8_t* u = v.data + h * v.stride;
      out[0] = packed(v.data, w, h, v.stride, 1, 1);
      out[1] = chroma(packed(u, w / 2, h / 2, s, 1, 1), true);
      out[2] = chroma(packed(u + (h / 2) * s, w / 2, h / 2, s, 1, 1), true);
      return 3;
    }
    default: break;
  }
  // A mosaic: the four sites of the 2x2 cell, each every other pixel of every other row.
  const int b = sample_bytes(v.format);
  for (int k = 0; k < 4; ++k) {
    const int dx = k & 1, dy = k >> 1;
    SamplePlane& p = out[k];
    p = packed(v.data + dy * v.stride + dx * b, w / 2, h / 2, 2 * v.stride, 1, b);
    p.step = 2 * b;
    p.scale_x = p.scale_y = 2, p.offset_x = dx, p.offset_y = dy;
  }
  return 4;
}

}  // namespace rsd::dsp
