#include "drivers/images_source.hpp"

#include <cstring>
#include <stdexcept>

#include "formats/image_file.hpp"

namespace rsd::drivers {

namespace {

std::string size_text(const FrameFormat& f) { return std::to_string(f.width) + " x " + std::to_string(f.height); }

}  // namespace

void ImagesSource::open() {
  if (cfg_.files.empty()) throw std::runtime_error("images: no image files");
  const dsp::Image first = formats::read_image(cfg_.files.front());  // names the file on error
  format_ = {first.width, first.height, first.format};
  next_ = 0;
}

dsp::RowTiming ImagesSource::timing() const {
  return dsp::RowTiming::full_frame(format_.height, cfg_.fps > 0 ? cfg_.fps : 30.0);
}

CaptureStatus ImagesSource::capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds) {
  if (next_ >= cfg_.files.size()) return CaptureStatus::EndOfStream;
  const std::string& file = cfg_.files[next_];
  const dsp::Image img = formats::read_image(file);
  const FrameFormat f{img.width, img.height, img.format};
  if (f.width != format_.width || f.height != format_.height)
    throw std::runtime_error(file + ": frame is " + size_text(f) + ", the first was " + size_text(format_));
  if (f.format != format_.format) throw std::runtime_error(file + ": pixel format differs from the first frame's");
  const size_t row = static_cast<size_t>(f.width) * dsp::bytes_per_pixel(f.format);
  for (int y = 0; y < f.height; ++y) std::memcpy(dst.row(y), img.data.data() + static_cast<size_t>(y) * img.stride(), row);
  meta = {};
  meta.sequence = next_;
  meta.first_row_ns = cfg_.fps > 0 ? static_cast<int64_t>(static_cast<double>(next_) * 1e9 / cfg_.fps) : 0;
  ++next_;
  return CaptureStatus::Frame;
}

}  // namespace rsd::drivers
