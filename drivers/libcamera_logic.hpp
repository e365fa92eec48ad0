// The libcamera source's logic that needs no camera: which libcamera pixel format delivers a
// frame slot's format, which stream role to ask for, which timestamp to trust and on which
// clock it is, the exposure, the page arithmetic of mapping a dmabuf plane, and the
// bookkeeping of requests completed on libcamera's thread and collected on ours.
#pragma once

#include <libcamera/pixel_format.h>
#include <libcamera/stream.h>

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/v4l2_logic.hpp"
#include "dsp/core/image.hpp"

namespace rsd::drivers::lc {

// ---- Pixel formats -------------------------------------------------------------------------

// libcamera names packed RGB as DRM does, by the bits of a little-endian word, so its RGB888
// lies in memory as B, G, R (V4L2's BGR24) and its BGR888 as R, G, B (V4L2's RGB24).
struct FormatInfo {
  libcamera::PixelFormat format;
  const char* name;
  v4l2::Layout layout;
};
// R8, YUYV, RGB888, BGR888; nullptr for any other format.
const FormatInfo* format_info(const libcamera::PixelFormat& f);
// The formats that deliver `want`, best first (see the .cpp for the order and why).
std::vector<FormatInfo> candidates(dsp::PixelFormat want);
// The first candidate for `want` that the stream offers; nullopt when none is.
std::optional<FormatInfo> choose_format(dsp::PixelFormat want, const std::vector<libcamera::PixelFormat>& offered);

// ---- Stream role ---------------------------------------------------------------------------

enum class Role { Auto, Viewfinder, Raw };
// "auto", "viewfinder", "raw"; false for anything else.
bool parse_role(std::string_view s, Role& out);
// Auto is Viewfinder: processed frames (R8, YUYV, RGB) from the ISP or format converter.
// Raw is the sensor's own data, which we can read only from an 8-bit monochrome sensor (R8).
libcamera::StreamRole stream_role(Role r);
const char* role_name(Role r);

// ---- Errors --------------------------------------------------------------------------------

// "no libcamera camera found (0 cameras listed)", or, when a camera id was asked for,
// "no libcamera camera found with id 'X' (2 cameras listed: a, b)".
std::string no_camera_message(const std::string& wanted_id, const std::vector<std::string>& listed);

// ---- Timestamps ----------------------------------------------------------------------------

// libcamera 0.0.3 documents controls::SensorTimestamp as "the time when the first row of the
// image sensor active array is exposed", on CLOCK_BOOTTIME; its pipeline handlers fill it from
// the V4L2 buffer timestamp, which is CLOCK_MONOTONIC. The two clocks differ by the time the
// system spent suspended, so where they differ the stamp itself tells which one it is on: a
// completed frame's stamp lies in the recent past of its own clock.
enum class Clock { Monotonic, Boottime };

class ClockResolver {
 public:
  explicit ClockResolver(std::int64_t max_latency_ns = 1'000'000'000) : max_latency_ns_(max_latency_ns) {}
  // Converts `ts` to CLOCK_MONOTONIC, given both clocks read when the request completed.
  // The first stamp that fits exactly one clock (0 <= now - ts <= max latency) settles the
  // clock for good; until then the documented CLOCK_BOOTTIME is assumed (harmless while the
  // clocks agree, which is whenever the machine has not been suspended).
  std::int64_t to_monotonic(std::int64_t ts, std::int64_t mono_now_ns, std::int64_t boot_now_ns);
  std::optional<Clock> settled() const { return settled_; }

 private:
  std::int64_t max_latency_ns_;
  std::optional<Clock> settled_;
};

// What the completion handler copies out of a finished libcamera Request, so that the rest
// happens on the capture thread without touching libcamera objects.
struct Completion {
  std::uint64_t cookie = 0;  // which of our requests
  bool cancelled = false;    // Request::RequestCancelled: no frame (stopping, or camera gone)
  bool frame_ok = true;      // FrameMetadata::FrameSuccess
  std::uint32_t sequence = 0;
  std::optional<std::int64_t> sensor_timestamp_ns;  // controls::SensorTimestamp
  std::uint64_t buffer_timestamp_ns = 0;            // FrameMetadata::timestamp (0: none)
  std::optional<std::int32_t> exposure_us;          // controls::ExposureTime
  std::size_t bytes_used = 0;
  std::int64_t mono_now_ns = 0, boot_now_ns = 0;  // both clocks, read at completion
};

enum class StampOrigin { SensorTimestamp, BufferTimestamp, CompletionTime };
struct FirstRowStamp {
  std::int64_t ns = 0;  // CLOCK_MONOTONIC, start of exposure of the first row read
  StampOrigin origin = StampOrigin::SensorTimestamp;
};

// SensorTimestamp (start of exposure of the first row, as documented) if present; else the
// buffer's timestamp, which the pipelines take from the same V4L2 stamp; both through the
// clock resolver. With neither, the completion time taken as end of frame, stepped back over
// the readout and the exposure exactly as v4l2::first_row_from_end_of_frame() does.
FirstRowStamp first_row_stamp(const Completion& c, ClockResolver& clocks, int rows, double line_delay_s,
                              double exposure_s);

// ExposureTime metadata (microseconds) in seconds, or the fallback when absent or not positive.
double exposure_seconds(std::optional<std::int32_t> exposure_us, double fallback_s);

// ---- Mapping a dmabuf plane ----------------------------------------------------------------

// mmap offsets must be page aligned; a plane may start anywhere in its dmabuf.
struct MapSpan {
  std::size_t map_offset = 0, map_length = 0;  // what to mmap
  std::size_t data_offset = 0;                  // where the plane starts in that mapping
};
MapSpan page_span(std::size_t plane_offset, std::size_t plane_length, std::size_t page_size);

// ---- Request bookkeeping -------------------------------------------------------------------

enum class Disposition {
  Deliver,   // copy the frame, then queue the request again
  Skip,      // a failed frame: queue the request again, deliver nothing
  Retire,    // cancelled: do not queue it again
};
Disposition dispose(const Completion& c);

enum class WaitResult { Ready, Timeout, Lost };

// Completed requests, handed from libcamera's thread (push) to the capture thread (pop), and
// the count of requests still with the camera.
class CompletionQueue {
 public:
  void queued();                 // a request went to the camera
  void push(Completion c);       // libcamera's thread: one came back
  void lose();                   // the camera was unplugged: pop() reports Lost from now on
  WaitResult pop(std::chrono::milliseconds timeout, Completion& out);
  std::size_t in_flight() const;
  void reset();  // after stop: nothing in flight, nothing pending, not lost

 private:
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::deque<Completion> done_;
  std::size_t in_flight_ = 0;
  bool lost_ = false;
};

}  // namespace rsd::drivers::lc
