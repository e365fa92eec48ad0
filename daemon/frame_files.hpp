// Rectified frames to files, beside the LCM output: rsd --output-dir OUT writes every frame
// as OUT/<frame>.png (the source's frame number, zero-padded to 6 digits: an images
// recording's numbers from its frames.csv), rsd --output-video FILE one encoded video.
//
// Thread contract: write() on the publishing thread only. Encoding a file takes time and
// allocates, so the daemon offers this on replays only, where the pipeline hands frames over
// without dropping (a live camera's hot path must never wait on a disk).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "dsp/core/image.hpp"

namespace rsd::formats {
class VideoWriter;
}

namespace rsd::daemon {

struct FrameFilesConfig {
  std::string dir;    // empty: no PNG files
  std::string video;  // empty: no video
  double fps = 30;    // the video's frame rate
};

class FrameFiles {
 public:
  // Creates the directory; throws std::runtime_error naming it (or the video) on failure.
  FrameFiles(const FrameFilesConfig& cfg, int width, int height);
  ~FrameFiles();
  // Throws std::runtime_error naming the file that could not be written.
  void write(const dsp::ImageView& img, uint64_t frame);
  uint64_t written() const { return written_; }
  // "OUT/000042.png".
  static std::string png_name(const std::string& dir, uint64_t frame);

 private:
  FrameFilesConfig cfg_;
  std::unique_ptr<formats::VideoWriter> video_;
  uint64_t written_ = 0;
};

}  // namespace rsd::daemon
