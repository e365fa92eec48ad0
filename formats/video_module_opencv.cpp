// The video module (formats/video_module.hpp) on OpenCV's FFmpeg video I/O.
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "formats/video_module.hpp"

namespace rsd::formats::video_module {
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

class OpenCvDecoder final : public Decoder {
 public:
  explicit OpenCvDecoder(const std::string& path) {
    if (!cap_.open(path, cv::CAP_FFMPEG) || !read_frame(cap_, first_))
      throw std::runtime_error(path + ": cannot decode a frame (not a video FFmpeg can read?)");
    have_first_ = true;
  }
  int width() const override { return first_.cols; }
  int height() const override { return first_.rows; }

  Next next(std::uint8_t* rgb, std::ptrdiff_t stride) override {
    if (have_first_) {
      bgr_ = first_;
      have_first_ = false;
    } else if (!read_frame(cap_, bgr_)) {
      return Next::End;
    }
    if (bgr_.cols != width() || bgr_.rows != height()) return Next::SizeChanged;
    if (bgr_.channels() == 1) cv::cvtColor(bgr_, rgb_, cv::COLOR_GRAY2RGB);
    else if (bgr_.channels() == 4) cv::cvtColor(bgr_, rgb_, cv::COLOR_BGRA2RGB);
    else cv::cvtColor(bgr_, rgb_, cv::COLOR_BGR2RGB);
    for (int y = 0; y < height(); ++y) std::memcpy(rgb + y * stride, rgb_.ptr(y), static_cast<size_t>(3 * width()));
    return Next::Frame;
  }

 private:
  cv::VideoCapture cap_;
  cv::Mat first_, bgr_, rgb_;
  bool have_first_ = false;
};

class OpenCvEncoder final : public Encoder {
 public:
  OpenCvEncoder(const std::string& path, int width, int height, double fps) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    int fourcc;
    if (ext == ".avi") fourcc = cv::VideoWriter::fourcc('M', 'J', 'P', 'G');
    else if (ext == ".mp4" || ext == ".mov" || ext == ".mkv") fourcc = cv::VideoWriter::fourcc('m', 'p', '4', 'v');
    else throw std::runtime_error(path + ": unknown video type '" + ext + "' (use .avi, .mp4, .mov or .mkv)");
    if (!(fps > 0)) fps = 30;
    if (!w_.open(path, cv::CAP_FFMPEG, fourcc, fps, cv::Size(width, height), true))
      throw std::runtime_error(path + ": cannot open for writing a " + std::to_string(width) + "x" + std::to_string(height) + " video");
    width_ = width, height_ = height;
  }

  void write(const std::uint8_t* data, std::ptrdiff_t stride, int channels, int bits) override {
    const int type = channels == 3 ? CV_8UC3 : bits == 16 ? CV_16UC1 : CV_8UC1;
    const cv::Mat m(height_, width_, type, const_cast<std::uint8_t*>(data), static_cast<size_t>(stride));
    if (type == CV_8UC1) cv::cvtColor(m, bgr_, cv::COLOR_GRAY2BGR);
    else if (type == CV_8UC3) cv::cvtColor(m, bgr_, cv::COLOR_RGB2BGR);
    else {
      m.convertTo(grey_, CV_8U, 1.0 / 256);  // a 16-bit frame's top 8 bits
      cv::cvtColor(grey_, bgr_, cv::COLOR_GRAY2BGR);
    }
    w_.write(bgr_);
  }

 private:
  cv::VideoWriter w_;
  cv::Mat bgr_, grey_;
  int width_ = 0, height_ = 0;
};

std::unique_ptr<Decoder> open_decoder(const std::string& path) { return std::make_unique<OpenCvDecoder>(path); }

std::unique_ptr<Encoder> open_encoder(const std::string& path, int width, int height, double fps) {
  return std::make_unique<OpenCvEncoder>(path, width, height, fps);
}

constexpr Api kApi{kVersion, &open_decoder, &open_encoder};

}  // namespace
}  // namespace rsd::formats::video_module

extern "C" __attribute__((visibility("default"))) const rsd::formats::video_module::Api* rsd_video_module_api() {
  return &rsd::formats::video_module::kApi;
}
