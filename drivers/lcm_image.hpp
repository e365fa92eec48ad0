// bot_core.image_t pixel formats (libbot2's FourCC codes) for rsd's pixel formats, both ways:
// what the publisher, the simulator's logs and every reader of logs agree on.
#pragma once

#include <bot_core/image_t.hpp>

#include <cstdint>
#include <optional>

#include "dsp/image.hpp"

namespace rsd::drivers {

inline int32_t fourcc(dsp::PixelFormat f) {
  switch (f) {
    case dsp::PixelFormat::Mono8: return bot_core::image_t::PIXEL_FORMAT_GRAY;
    case dsp::PixelFormat::Mono16: return bot_core::image_t::PIXEL_FORMAT_LE_GRAY16;
    case dsp::PixelFormat::Rgb8: return bot_core::image_t::PIXEL_FORMAT_RGB;
  }
  return bot_core::image_t::PIXEL_FORMAT_INVALID;
}

inline std::optional<dsp::PixelFormat> pixel_format(int32_t fourcc_code) {
  if (fourcc_code == bot_core::image_t::PIXEL_FORMAT_GRAY) return dsp::PixelFormat::Mono8;
  if (fourcc_code == bot_core::image_t::PIXEL_FORMAT_LE_GRAY16) return dsp::PixelFormat::Mono16;
  if (fourcc_code == bot_core::image_t::PIXEL_FORMAT_RGB) return dsp::PixelFormat::Rgb8;
  return std::nullopt;
}

}  // namespace rsd::drivers
