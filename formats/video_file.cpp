#include "formats/video_file.hpp"

#include <filesystem>
#include <stdexcept>

#include "dsp/core/pixel_conversion.hpp"
#include "formats/video_module_loader.hpp"

namespace rsd::formats {

struct VideoReader::Impl {
  std::unique_ptr<video_module::Decoder> decoder;
};

VideoReader::VideoReader(const std::string& path) : impl_(std::make_unique<Impl>()), path_(path) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": no such video file");
  impl_->decoder = video_module_api().open_decoder(path);
}

VideoReader::~VideoReader() = default;

int VideoReader::width() const { return impl_->decoder->width(); }
int VideoReader::height() const { return impl_->decoder->height(); }

bool VideoReader::next(dsp::Image& out) {
  if (out.width != width() || out.height != height() || out.format != dsp::PixelFormat::Rgb8)
    out = dsp::Image(width(), height(), dsp::PixelFormat::Rgb8);
  switch (impl_->decoder->next(out.data.data(), out.stride())) {
    case video_module::Decoder::Next::End:
      return false;
    case video_module::Decoder::Next::SizeChanged:
      throw std::runtime_error(path_ + ": frame " + std::to_string(position_) + " changes the video's size");
    case video_module::Decoder::Next::Frame:
      break;
  }
  ++position_;
  return true;
}

struct VideoWriter::Impl {
  std::unique_ptr<video_module::Encoder> encoder;
  dsp::Image converted;  // YUV and mosaic frames in RGB
  int width = 0, height = 0;
};

VideoWriter::VideoWriter(const std::string& path, int width, int height, double fps)
    : impl_(std::make_unique<Impl>()), path_(path) {
  impl_->encoder = video_module_api().open_encoder(path, width, height, fps);
  impl_->width = width, impl_->height = height;
}

VideoWriter::~VideoWriter() = default;

void VideoWriter::write(const dsp::ImageView& img) {
  if (img.width != impl_->width || img.height != impl_->height)
    throw std::runtime_error(path_ + ": frame size differs from the video's");
  if (img.format != dsp::PixelFormat::Mono8 && img.format != dsp::PixelFormat::Mono16 && img.format != dsp::PixelFormat::Rgb8) {
    if (impl_->converted.width != img.width) impl_->converted = dsp::Image(img.width, img.height, dsp::PixelFormat::Rgb8);
    dsp::convert_to_rgb(img, impl_->converted.view());  // YUV and mosaics: as they look
    return write(impl_->converted.view());
  }
  const int channels = img.format == dsp::PixelFormat::Rgb8 ? 3 : 1;
  impl_->encoder->write(img.data, img.stride, channels, img.format == dsp::PixelFormat::Mono16 ? 16 : 8);
  ++frames_;
}

}  // namespace rsd::formats
