#include "formats/video_file.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "dsp/core/pixel_conversion.hpp"

namespace rsd::formats {

struct VideoReader::Impl {
  cv::VideoCapture cap;
  cv::Mat first, bgr, rgb;
  bool have_first = false;
};

namespace {

// OpenCV's FFmpeg reader can give no frame once in the middle of a file and the next frame on the
// next call (GoPro's MP4s, whose metadata tracks interleave with the video, do it about a second
// in): a few calls without a frame, not one, are the end. Without this an images recording read
// 28 of a GoPro clip's 362 frames.
bool read_frame(cv::VideoCapture& cap, cv::Mat& m) {
  for (int attempt = 0; attempt < 4; ++attempt)
    if (cap.read(m) && !m.empty()) return true;
  return false;
}

}  // namespace

VideoReader::VideoReader(const std::string& path) : impl_(std::make_unique<Impl>()), path_(path) {
  if (!std::filesystem::exists(path)) throw std::runtime_error(path + ": no such video file");
  if (!impl_->cap.open(path, cv::CAP_FFMPEG) || !read_frame(impl_->cap, impl_->first))
    throw std::runtime_error(path + ": cannot decode a frame (not a video FFmpeg can read?)");
  impl_->have_first = true;
}

VideoReader::~VideoReader() = default;

int VideoReader::width() const { return impl_->first.cols; }
int VideoReader::height() const { return impl_->first.rows; }

bool VideoReader::next(dsp::Image& out) {
  cv::Mat& m = impl_->bgr;
  if (impl_->have_first) {
    m = impl_->first;
    impl_->have_first = false;
  } else if (!read_frame(impl_->cap, m)) {
    return false;
  }
  if (m.cols != width() || m.rows != height())
    throw std::runtime_error(path_ + ": frame " + std::to_string(position_) + " changes the video's size");
  if (m.channels() == 1) cv::cvtColor(m, impl_->rgb, cv::COLOR_GRAY2RGB);
  else if (m.channels() == 4) cv::cvtColor(m, impl_->rgb, cv::COLOR_BGRA2RGB);
  else cv::cvtColor(m, impl_->rgb, cv::COLOR_BGR2RGB);
  if (out.width != width() || out.height != height() || out.format != dsp::PixelFormat::Rgb8)
    out = dsp::Image(width(), height(), dsp::PixelFormat::Rgb8);
  for (int y = 0; y < out.height; ++y)
    std::memcpy(out.data.data() + static_cast<size_t>(y) * out.stride(), impl_->rgb.ptr(y), static_cast<size_t>(out.stride()));
  ++position_;
  return true;
}

struct VideoWriter::Impl {
  cv::VideoWriter w;
  cv::Mat bgr;
  dsp::Image converted;  // YUV and mosaic frames in RGB
  int width = 0, height = 0;
};

VideoWriter::VideoWriter(const std::string& path, int width, int height, double fps)
    : impl_(std::make_unique<Impl>()), path_(path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  int fourcc;
  if (ext == ".avi") fourcc = cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
  else if (ext == ".mp4" || ext == ".mov" || ext == ".mkv") fourcc = cv::VideoWriter::fourcc('m', 'p', '4', 'v');
  else throw std::runtime_error(path + ": unknown video type '" + ext + "' (use .avi, .mp4, .mov or .mkv)");
  if (!(fps > 0)) fps = 30;
  if (!impl_->w.open(path, cv::CAP_FFMPEG, fourcc, fps, cv::Size(width, height), true))
    throw std::runtime_error(path + ": cannot open for writing a " + std::to_string(width) + "x" + std::to_string(height) + " video");
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
  const int type = img.format == dsp::PixelFormat::Mono8 ? CV_8UC1 : img.format == dsp::PixelFormat::Rgb8 ? CV_8UC3 : CV_16UC1;
  const cv::Mat m(img.height, img.width, type, img.data, static_cast<size_t>(img.stride));
  if (type == CV_8UC1) cv::cvtColor(m, impl_->bgr, cv::COLOR_GRAY2BGR);
  else if (type == CV_8UC3) cv::cvtColor(m, impl_->bgr, cv::COLOR_RGB2BGR);
  else {
    cv::Mat g;
    m.convertTo(g, CV_8U, 1.0 / 256);
    cv::cvtColor(g, impl_->bgr, cv::COLOR_GRAY2BGR);
  }
  impl_->w.write(impl_->bgr);
  ++frames_;
}

}  // namespace rsd::formats
