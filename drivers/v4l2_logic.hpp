// The V4L2 source's logic that needs no real device: pixel formats and how their rows become
// frame slots, format negotiation and buffer bookkeeping through the V4l2Device seam,
// timestamp conversion to the start of exposure of the first row read, sequence-gap
// counting, and what an errno means for the daemon (camera missing or lost vs. a bug).
//
// The row copy and the sequence tracker serve the libcamera source too: libcamera's buffers
// are V4L2 buffers underneath, with the same layouts and the same 32-bit counters.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/camera_source.hpp"
#include "drivers/v4l2_device.hpp"
#include "dsp/core/image.hpp"

namespace rsd::drivers::v4l2 {

// ---- Pixel layouts: how one row of a buffer becomes one row of a frame slot ----------------

// The frame's pixel format, and whether the buffer's colour bytes come as B, G, R (swapped into
// R, G, B). Every other layout is the format's own (pixel_format.hpp: V4L2's single-planar
// layouts, which the frame slots share) and is copied as it is: YUYV, NV12, I420 and the Bayer
// mosaics reach the rectifier natively.
struct Layout {
  dsp::PixelFormat format = dsp::PixelFormat::Mono8;
  bool bgr = false;
  bool operator==(const Layout&) const = default;
  static const Layout Grey8, Grey16, Rgb24, Bgr24;
};
inline constexpr Layout Layout::Grey8{dsp::PixelFormat::Mono8, false};
inline constexpr Layout Layout::Grey16{dsp::PixelFormat::Mono16, false};  // little-endian, as every host we build for
inline constexpr Layout Layout::Rgb24{dsp::PixelFormat::Rgb8, false};
inline constexpr Layout Layout::Bgr24{dsp::PixelFormat::Rgb8, true};
inline constexpr Layout native(dsp::PixelFormat f) { return {f, false}; }
inline dsp::PixelFormat output_format(Layout l) { return l.format; }

// Copies a frame whose rows are `src_stride` bytes apart (padding honoured) into `dst`.
// Returns false, touching nothing, when `src_len` is too short for dst.height rows (a
// truncated frame). Throws std::invalid_argument when dst's format is not output_format(l),
// its stride is too short or it has no pixels.
bool copy_frame(const std::uint8_t* src, std::size_t src_len, std::size_t src_stride, Layout l,
                const dsp::ImageView& dst);

// ---- V4L2 pixel formats we read ------------------------------------------------------------

struct PixelInfo {
  std::uint32_t fourcc;
  const char* name;  // as the config spells it
  Layout layout;
};
// GREY, Y16, RGB24, YUYV, NV12, YU12 (I420) and the 8 and 16-bit Bayer mosaics; nullptr for
// any other fourcc.
const PixelInfo* pixel_info(std::uint32_t fourcc);
// Parses a config name ("GREY", "Y16", "YUYV", "RGB24", "NV12", "YU12", "RGGB", "BYR2", ...,
// V4L2's fourcc names); false for anything else.
// Every name parse_pixel_format accepts, comma separated.
std::string pixel_format_names();
bool parse_pixel_format(std::string_view name, std::uint32_t& fourcc);
// "GREY", "MJPG", "Y16 ": the four characters, unprintable ones as '?'.
std::string fourcc_name(std::uint32_t fourcc);

// The offered format closest to the requested one (see the preference table in the .cpp);
// 0 when the device offers none we can read.
std::uint32_t choose_pixel_format(std::uint32_t requested, const std::vector<std::uint32_t>& offered);

// The frame size closest to width x height among the sizes VIDIOC_ENUM_FRAMESIZES listed
// (discrete sizes: least |dw| + |dh|; stepwise/continuous: clamped and rounded to the step).
// An empty list (the driver cannot enumerate) leaves the request for S_FMT to adjust.
struct Size {
  int width = 0, height = 0;
};
Size choose_frame_size(Size requested, const std::vector<v4l2_frmsizeenum>& sizes);

// ---- Negotiation through the device --------------------------------------------------------

struct FormatRequest {
  int width = 640, height = 480;
  std::uint32_t fourcc = V4L2_PIX_FMT_GREY;
  double fps = 30;
};

struct Negotiated {
  int width = 0, height = 0;
  std::uint32_t fourcc = 0;
  Layout layout = Layout::Grey8;
  std::uint32_t bytesperline = 0, sizeimage = 0;
  double fps = 0;
  bool fps_known = false;          // false: the driver would not say; fps is the request
  std::vector<std::string> notes;  // every way the result differs from the request
  FrameFormat frame_format() const { return {width, height, output_format(layout)}; }
};

// Throws std::runtime_error unless the node can capture video by streaming I/O.
void check_capabilities(const v4l2_capability& cap, const std::string& path);
// ENUM_FMT / ENUM_FRAMESIZES, then S_FMT and S_PARM; accepts what the driver returns and notes
// the differences. Throws CameraError if the camera goes away meanwhile, std::runtime_error
// if it offers nothing we can read.
Negotiated negotiate(V4l2Device& dev, const FormatRequest& req, const std::string& path);

// The exposure the driver reports (V4L2_CID_EXPOSURE_ABSOLUTE, in 100 us units), in seconds;
// false when it has no such control.
bool query_exposure(V4l2Device& dev, double& exposure_s);

// ---- Buffer bookkeeping --------------------------------------------------------------------

// The mmap'ed buffers of one streaming session: REQBUFS, QUERYBUF, mmap and QBUF on
// allocate(); munmap and REQBUFS(0) on release(). The device must outlive the ring.
class BufferRing {
 public:
  BufferRing(V4l2Device& dev, std::string path) : dev_(dev), path_(std::move(path)) {}
  ~BufferRing() { release(); }
  BufferRing(const BufferRing&) = delete;
  BufferRing& operator=(const BufferRing&) = delete;

  // Asks for `count` buffers (the driver may grant another number, at least one) and queues
  // them all. Throws CameraError / std::runtime_error as map_errno() says.
  void allocate(unsigned count);
  void release() noexcept;  // call after STREAMOFF, which dequeues everything
  std::size_t count() const { return buffers_.size(); }
  unsigned queued() const { return queued_; }
  std::span<const std::uint8_t> data(std::uint32_t index) const;
  void queue(std::uint32_t index);
  // DQBUF: true with `buf` filled, false when no buffer is ready (EAGAIN).
  bool dequeue(v4l2_buffer& buf);

 private:
  void map_one(std::uint32_t index);
  struct Mapped {
    void* addr = nullptr;
    std::size_t length = 0;
  };
  V4l2Device& dev_;
  std::string path_;
  std::vector<Mapped> buffers_;
  unsigned queued_ = 0;
};

// ---- Timestamps ----------------------------------------------------------------------------

struct FirstRowTime {
  std::int64_t ns = 0;           // CLOCK_MONOTONIC: start of exposure of the first row read
  bool from_driver_clock = true;  // false: the driver's clock is unknown; ns is estimated
                                 // from the dequeue time (late by the delivery latency)
};

// A V4L2 end-of-frame stamp (the last row read out) to the first row's start of exposure:
// ns - round(((rows - 1) * line_delay_s + exposure_s) * 1e9). See the .cpp for why.
std::int64_t first_row_from_end_of_frame(std::int64_t eof_ns, int rows, double line_delay_s,
                                         double exposure_s);

// Reads buf.flags: CLOCK_MONOTONIC stamps are used, start-of-exposure (TSTAMP_SRC_SOE) as
// they are, end-of-frame (TSTAMP_SRC_EOF) through first_row_from_end_of_frame(). Stamps on
// an unknown or copied clock are replaced by `dequeue_mono_ns`, taken as end of frame.
FirstRowTime first_row_start(const v4l2_buffer& buf, int rows, double line_delay_s, double exposure_s,
                             std::int64_t dequeue_mono_ns);

// ---- Sequence numbers ----------------------------------------------------------------------

// Follows a driver's 32-bit frame counter: unwraps it to 64 bits and counts the frames missing
// between consecutive numbers. A counter that goes backwards (or repeats) means the stream
// restarted: counted as a restart, not as drops, and the 64-bit sequence goes on by one.
class SequenceTracker {
 public:
  std::uint64_t update(std::uint32_t seq);
  std::uint64_t dropped() const { return dropped_; }
  std::uint64_t restarts() const { return restarts_; }
  void reset() { *this = SequenceTracker(); }

 private:
  bool started_ = false;
  std::uint32_t last_ = 0;
  std::uint64_t unwrapped_ = 0, dropped_ = 0, restarts_ = 0;
};

// ---- What an errno means -------------------------------------------------------------------

// errno values that mean the camera is gone (unplugged, driver reset): ENODEV, ENXIO, EIO,
// ENOENT, EPIPE, ESHUTDOWN. The daemon retries on these.
bool camera_lost(int err);
// CameraError for camera_lost() errors ("camera at P lost during CALL (...)"), and for EBUSY
// (another program streams from it), std::runtime_error naming the call otherwise.
[[noreturn]] void throw_errno(int err, std::string_view call, const std::string& path);
// The error for a failed open(2) of `path`: always a CameraError (missing, no permission,
// busy: all things the daemon can wait out), worded for the person reading the log.
CameraError open_error(int err, const std::string& path);

}  // namespace rsd::drivers::v4l2
