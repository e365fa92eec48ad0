// The video module's interface: the codec half of formats/video_file, built as a module of its own
// (rsd_video_opencv.so, formats/video_module_opencv.cpp: OpenCV's FFmpeg video I/O) and loaded by
// video_file on the first video a process opens. OpenCV's video I/O needs about 240 shared
// libraries (FFmpeg, GStreamer, camera SDKs); linked into every program that may meet a video it
// made each start of rsd, of a tool or of a test cost about 0.4 s of CPU in the dynamic loader,
// while only images recordings that hold a video and `--output-video` use it.
//
// Errors throw std::runtime_error (the module and its loader share one C++ runtime).
// Thread contract: a Decoder or Encoder is used by one thread at a time; the entry point may be
// called from any thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace rsd::formats::video_module {

// Bumped whenever these declarations change: the loader refuses a module of another version.
inline constexpr int kVersion = 1;

class Decoder {
 public:
  virtual ~Decoder() = default;
  // The video's size: its first frame's.
  virtual int width() const = 0;
  virtual int height() const = 0;
  enum class Next { Frame, End, SizeChanged };
  // The next frame as packed RGB, 3 x width() bytes per row, rows `stride` bytes apart.
  virtual Next next(std::uint8_t* rgb, std::ptrdiff_t stride) = 0;
};

class Encoder {
 public:
  virtual ~Encoder() = default;
  // A frame of the encoder's size: `channels` 1 (grey, 8 or 16 bits) or 3 (RGB, 8 bits).
  virtual void write(const std::uint8_t* data, std::ptrdiff_t stride, int channels, int bits) = 0;
};

struct Api {
  int version;
  // Opens a video and decodes its first frame; throws naming the file if it cannot.
  std::unique_ptr<Decoder> (*open_decoder)(const std::string& path);
  // Opens a video for writing: the codec follows the extension (.avi Motion-JPEG; .mp4, .mov,
  // .mkv MPEG-4 Part 2); throws naming the file if it cannot.
  std::unique_ptr<Encoder> (*open_encoder)(const std::string& path, int width, int height, double fps);
};

}  // namespace rsd::formats::video_module

// The module's one exported symbol.
extern "C" const rsd::formats::video_module::Api* rsd_video_module_api();
