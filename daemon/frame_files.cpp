#include "daemon/frame_files.hpp"

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "formats/image_file.hpp"
#include "formats/video_file.hpp"

namespace rsd::daemon {

FrameFiles::FrameFiles(const FrameFilesConfig& cfg, int width, int height) : cfg_(cfg) {
  if (!cfg_.dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(cfg_.dir, ec);
    if (ec || !std::filesystem::is_directory(cfg_.dir))
      throw std::runtime_error("--output-dir " + cfg_.dir + ": cannot create the directory" + (ec ? ": " + ec.message() : ""));
  }
  if (!cfg_.video.empty()) video_ = std::make_unique<formats::VideoWriter>(cfg_.video, width, height, cfg_.fps);
}

FrameFiles::~FrameFiles() = default;

std::string FrameFiles::png_name(const std::string& dir, uint64_t frame) {
  char name[32];
  std::snprintf(name, sizeof name, "%06llu.png", static_cast<unsigned long long>(frame));
  return (std::filesystem::path(dir) / name).string();
}

void FrameFiles::write(const dsp::ImageView& img, uint64_t frame) {
  if (!cfg_.dir.empty()) formats::write_png(png_name(cfg_.dir, frame), img);  // names the file on failure
  if (video_) video_->write(img);
  ++written_;
}

}  // namespace rsd::daemon
