// Image files (PNG or binary PGM) as a camera: one frame per file, in the order given. The
// tools read captures this way (rsd-calib's LED frames), through the one source interface.
//
// Thread contract: one thread calls open(), start() and capture(), as for every source.
#pragma once

#include <string>
#include <vector>

#include "drivers/camera_source.hpp"

namespace rsd::drivers {

struct ImagesConfig {
  std::vector<std::string> files;
  double fps = 0;  // frame rate for stamps (frame k at k / fps); 0: the frames carry no time
};

class ImagesSource final : public CameraSource {
 public:
  explicit ImagesSource(ImagesConfig cfg) : cfg_(std::move(cfg)) {}
  std::string name() const override { return "images"; }
  // Reads the first file: its size and pixel format are every frame's. Throws
  // std::runtime_error naming the file if it cannot be read.
  void open() override;
  FrameFormat format() const override { return format_; }
  dsp::RowTiming timing() const override;
  void start() override { next_ = 0; }
  // EndOfStream after the last file; throws std::runtime_error naming a file that cannot be
  // read or whose size or format differs from the first.
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) override;
  void stop() override {}
  // The file of the frame capture() delivered last.
  const std::string& current_file() const { return cfg_.files.at(next_ - 1); }
  bool stamped() const { return cfg_.fps > 0; }

 private:
  ImagesConfig cfg_;
  FrameFormat format_;
  size_t next_ = 0;
};

}  // namespace rsd::drivers
