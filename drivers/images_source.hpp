// Pictures as a camera: image files (PNG or binary PGM) or the frames of a video, one frame
// each, in the order given. The tools read captures this way (rsd-calib's LED frames, an
// images recording's pictures), and the recording source plays them to the daemon.
//
// Thread contract: one thread calls open(), start() and capture(), as for every source.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "drivers/camera_source.hpp"

namespace rsd::formats {
class VideoReader;
}

namespace rsd::drivers {

struct ImagesConfig {
  std::vector<std::string> files;  // the pictures; or, with `video`, unused
  std::string video;               // a video file instead: its frames, decoded in order
  std::vector<long> video_frames;  // with `video`: the indices to deliver (ascending); empty: all
  double fps = 0;  // frame rate for stamps (frame k at k / fps); 0: the frames carry no time
  // Optional, one per picture: each frame's stamp (first row, seconds on the source's clock,
  // overriding fps) and its number (FrameMeta::sequence; default the picture's index).
  std::vector<double> stamps_s;
  std::vector<uint64_t> numbers;
};

class ImagesSource final : public CameraSource {
 public:
  explicit ImagesSource(ImagesConfig cfg);
  ~ImagesSource() override;
  std::string name() const override { return "images"; }
  // Reads the first picture: its size and pixel format are every frame's. Throws
  // std::runtime_error naming the file if it cannot be read.
  void open() override;
  FrameFormat format() const override { return format_; }
  dsp::RowTiming timing() const override;
  void start() override;
  // EndOfStream after the last picture; throws std::runtime_error naming a file that cannot
  // be read or whose size or format differs from the first (the next call goes on with the
  // picture after it).
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) override;
  void stop() override {}
  // The file (or "video#index") of the frame capture() delivered last.
  std::string current_file() const;
  bool stamped() const { return cfg_.fps > 0 || !cfg_.stamps_s.empty(); }
  size_t count() const { return cfg_.video.empty() ? cfg_.files.size() : cfg_.video_frames.size(); }
  size_t delivered() const { return next_; }

 private:
  dsp::Image read(size_t k);
  ImagesConfig cfg_;
  FrameFormat format_;
  size_t next_ = 0;
  std::unique_ptr<formats::VideoReader> video_;
  dsp::Image frame_;  // a video's decoded frame
};

}  // namespace rsd::drivers
