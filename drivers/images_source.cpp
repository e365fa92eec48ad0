#include "drivers/images_source.hpp"

#include "dsp/core/image_planes.hpp"
#include "dsp/core/stamp.hpp"
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "formats/image_file.hpp"
#include "formats/video_file.hpp"

namespace rsd::drivers {

namespace {

std::string size_text(const FrameFormat& f) { return std::to_string(f.width) + " x " + std::to_string(f.height); }

}  // namespace

ImagesSource::ImagesSource(ImagesConfig cfg) : cfg_(std::move(cfg)) {}
ImagesSource::~ImagesSource() = default;

void ImagesSource::open() {
  if (!cfg_.video.empty() && cfg_.video_frames.empty()) {
    // Every frame: count them once (the index list keeps capture() simple).
    formats::VideoReader r(cfg_.video);
    dsp::Image img;
    while (r.next(img)) cfg_.video_frames.push_back(r.position() - 1);
  }
  if (count() == 0) throw std::runtime_error(cfg_.video.empty() ? "images: no image files" : cfg_.video + ": no frames");
  if (!cfg_.stamps_s.empty() && cfg_.stamps_s.size() != count())
    throw std::invalid_argument("images: " + std::to_string(cfg_.stamps_s.size()) + " stamps for " + std::to_string(count()) + " pictures");
  for (size_t k = 0; k < cfg_.stamps_s.size(); ++k)
    if (!dsp::Stamp::from_s(cfg_.stamps_s[k]))
      throw std::invalid_argument("images: stamp " + std::to_string(k) + " is beyond rsd's window for times (dsp::Stamp)");
  start();
  const dsp::Image first = read(0);  // names the file on error
  format_ = {first.width, first.height, first.format};
  start();
}

void ImagesSource::start() {
  next_ = 0;
  if (!cfg_.video.empty()) video_ = std::make_unique<formats::VideoReader>(cfg_.video);
}

dsp::RowTiming ImagesSource::timing() const {
  return dsp::RowTiming::full_frame(format_.height, cfg_.fps > 0 ? cfg_.fps : 30.0);
}

std::string ImagesSource::current_file() const {
  const size_t k = next_ - 1;
  return cfg_.video.empty() ? cfg_.files.at(k) : cfg_.video + "#" + std::to_string(cfg_.video_frames.at(k));
}

// Picture k: a file, or the video decoded up to its frame.
dsp::Image ImagesSource::read(size_t k) {
  if (cfg_.video.empty()) return formats::read_image(cfg_.files[k]);
  const long want = cfg_.video_frames[k];
  while (video_->position() <= want)
    if (!video_->next(frame_))
      throw std::runtime_error(cfg_.video + ": ends after " + std::to_string(video_->position()) + " frames, before frame " +
                               std::to_string(want));
  return frame_;
}

CaptureStatus ImagesSource::capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds) {
  if (next_ >= count()) return CaptureStatus::EndOfStream;
  const size_t k = next_++;  // past it even when it throws: a caller may go on with the next one
  const dsp::Image img = read(k);
  const FrameFormat f{img.width, img.height, img.format};
  const std::string what = cfg_.video.empty() ? cfg_.files[k] : cfg_.video + " frame " + std::to_string(cfg_.video_frames[k]);
  if (f.width != format_.width || f.height != format_.height)
    throw std::runtime_error(what + ": frame is " + size_text(f) + ", the first was " + size_text(format_));
  if (f.format != format_.format) throw std::runtime_error(what + ": pixel format differs from the first frame's");
  dsp::copy_image(img.data.data(), img.stride(), dst);
  meta = {};
  meta.sequence = cfg_.numbers.empty() ? k : cfg_.numbers.at(k);
  if (!cfg_.stamps_s.empty()) meta.first_row_ns = dsp::Stamp::from_s(cfg_.stamps_s[k])->ns();  // checked at open
  else meta.first_row_ns = cfg_.fps > 0 ? static_cast<int64_t>(static_cast<double>(k) * 1e9 / cfg_.fps) : 0;
  return CaptureStatus::Frame;
}

}  // namespace rsd::drivers
