// Video files, read frame by frame and written, through OpenCV's video I/O (FFmpeg): an images
// recording's `observations.video` and rsd --output-video. Errors throw std::runtime_error
// naming the file.
//
// Thread contract: one object per thread.
#pragma once

#include <memory>
#include <string>

#include "dsp/core/image.hpp"

namespace rsd::formats {

class VideoReader {
 public:
  // Opens the file and decodes its first frame (which fixes the size). Frames come out as Rgb8.
  explicit VideoReader(const std::string& path);
  ~VideoReader();
  int width() const;
  int height() const;
  // Decodes the next frame into `out` (Rgb8, the video's size); false at the end.
  bool next(dsp::Image& out);
  // Frames decoded so far (the index of the next one).
  long position() const { return position_; }
  const std::string& path() const { return path_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  long position_ = 0;
};

class VideoWriter {
 public:
  // The codec follows the extension: .avi Motion-JPEG, .mp4 / .mov / .mkv MPEG-4 Part 2.
  VideoWriter(const std::string& path, int width, int height, double fps);
  ~VideoWriter();
  // Mono8, Mono16 (its top 8 bits) or Rgb8 of the size given.
  void write(const dsp::ImageView& img);
  long frames() const { return frames_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  long frames_ = 0;
};

}  // namespace rsd::formats
