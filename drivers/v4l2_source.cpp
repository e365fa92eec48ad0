#include "drivers/v4l2_source.hpp"
#include "dsp/core/input_limits.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <stdexcept>

namespace rsd::drivers {

// ---- The real device: the only code here that talks to the kernel -------------------------

namespace {

class KernelV4l2Device final : public V4l2Device {
 public:
  explicit KernelV4l2Device(int fd) : fd_(fd) {}
  ~KernelV4l2Device() override { ::close(fd_); }
  KernelV4l2Device(const KernelV4l2Device&) = delete;
  KernelV4l2Device& operator=(const KernelV4l2Device&) = delete;

  int query_cap(v4l2_capability& c) override { return xioctl(VIDIOC_QUERYCAP, &c); }
  int enum_format(v4l2_fmtdesc& d) override { return xioctl(VIDIOC_ENUM_FMT, &d); }
  int enum_frame_size(v4l2_frmsizeenum& s) override { return xioctl(VIDIOC_ENUM_FRAMESIZES, &s); }
  int set_format(v4l2_format& f) override { return xioctl(VIDIOC_S_FMT, &f); }
  int get_parm(v4l2_streamparm& p) override { return xioctl(VIDIOC_G_PARM, &p); }
  int set_parm(v4l2_streamparm& p) override { return xioctl(VIDIOC_S_PARM, &p); }
  int get_control(v4l2_control& c) override { return xioctl(VIDIOC_G_CTRL, &c); }
  int request_buffers(v4l2_requestbuffers& r) override { return xioctl(VIDIOC_REQBUFS, &r); }
  int query_buffer(v4l2_buffer& b) override { return xioctl(VIDIOC_QUERYBUF, &b); }
  int queue_buffer(v4l2_buffer& b) override { return xioctl(VIDIOC_QBUF, &b); }
  int dequeue_buffer(v4l2_buffer& b) override { return xioctl(VIDIOC_DQBUF, &b); }
  int stream_on() override { return stream(VIDIOC_STREAMON); }
  int stream_off() override { return stream(VIDIOC_STREAMOFF); }

  int wait_readable(int timeout_ms, bool& ready) override {
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, timeout_ms);
    if (r < 0) return errno;
    // POLLERR/POLLHUP (a camera unplugged, or nothing queued) also count as ready: DQBUF then
    // says which with its errno.
    ready = r > 0;
    return 0;
  }
  int map(std::size_t length, std::uint32_t offset, void*& addr) override {
    void* a = ::mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, offset);
    if (a == MAP_FAILED) return errno;
    addr = a;
    return 0;
  }
  void unmap(void* addr, std::size_t length) override { ::munmap(addr, length); }

 private:
  // ioctl with EINTR retried; 0 or errno.
  int xioctl(unsigned long request, void* arg) {
    int r;
    do r = ::ioctl(fd_, request, arg);
    while (r < 0 && errno == EINTR);
    return r < 0 ? errno : 0;
  }
  int stream(unsigned long request) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    return xioctl(request, &type);
  }
  int fd_;
};

std::int64_t monotonic_now_ns() {
  timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

bool finite_non_negative(double v) { return std::isfinite(v) && v >= 0; }

}  // namespace

std::unique_ptr<V4l2Device> open_v4l2_device(const std::string& path) {
  // Non-blocking, so that DQBUF never waits: poll() does, with the caller's timeout.
  const int fd = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw v4l2::open_error(errno, path);
  return std::make_unique<KernelV4l2Device>(fd);
}

// ---- Configuration -------------------------------------------------------------------------

void validate(const V4l2Config& c) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("v4l2 config: " + what); };
  std::uint32_t fourcc = 0;
  if (c.device.empty()) bad("device: empty path");
  if (!dsp::limits::side_ok(c.width) || !dsp::limits::side_ok(c.height))
    bad(std::string("width/height: expected ") + dsp::limits::kSide.text + ", got " + std::to_string(c.width) + "x" + std::to_string(c.height));
  if (!(std::isfinite(c.fps) && c.fps > 0 && c.fps <= 10000)) bad("fps: expected a rate in (0, 10000]");
  if (c.buffers < 1 || c.buffers > 64) bad("buffers: expected 1..64, got " + std::to_string(c.buffers));
  if (!v4l2::parse_pixel_format(c.pixel_format, fourcc))
    bad("pixel_format: expected GREY, Y16, YUYV or RGB24, got '" + c.pixel_format + "'");
  if (!finite_non_negative(c.line_delay_s)) bad("line_delay_s: expected >= 0 seconds");
  if (!finite_non_negative(c.exposure_s)) bad("exposure_s: expected >= 0 seconds");
}

// ---- The source ----------------------------------------------------------------------------

V4l2Source::V4l2Source(V4l2Config cfg, V4l2Opener opener, std::function<std::int64_t()> clock)
    : cfg_(std::move(cfg)),
      opener_(opener ? std::move(opener) : V4l2Opener(open_v4l2_device)),
      clock_(clock ? std::move(clock) : std::function<std::int64_t()>(monotonic_now_ns)) {
  validate(cfg_);
  v4l2::parse_pixel_format(cfg_.pixel_format, fourcc_);
}

V4l2Source::~V4l2Source() { close(); }

void V4l2Source::open() {
  close();
  try {
    dev_ = opener_(cfg_.device);
    v4l2_capability cap{};
    if (const int err = dev_->query_cap(cap)) {
      if (v4l2::camera_lost(err)) v4l2::throw_errno(err, "VIDIOC_QUERYCAP", cfg_.device);
      throw std::runtime_error(cfg_.device + " is not a V4L2 device (VIDIOC_QUERYCAP: " + std::strerror(err) + ")");
    }
    v4l2::check_capabilities(cap, cfg_.device);
    negotiated_ = v4l2::negotiate(*dev_, {cfg_.width, cfg_.height, fourcc_, cfg_.fps}, cfg_.device);
    timing_ = dsp::RowTiming::full_frame(negotiated_.height, negotiated_.fps, cfg_.readout);
    if (cfg_.line_delay_s > 0) timing_.line_delay_s = cfg_.line_delay_s;
    if (timing_.frame_readout_s() > timing_.frame_period_s() * (1 + 1e-9))
      throw std::invalid_argument("v4l2 config: line_delay_s x " + std::to_string(negotiated_.height) +
                                  " rows exceeds the frame period at " + std::to_string(negotiated_.fps) + " fps");
    refresh_exposure();
    if (timing_.exposure_s == 0)
      negotiated_.notes.push_back("exposure unknown (set exposure_s): end-of-frame stamps will be late by it");
    ring_ = std::make_unique<v4l2::BufferRing>(*dev_, cfg_.device);
  } catch (...) {
    close();
    throw;
  }
}

// A fixed exposure from the config wins; otherwise the driver's current setting, which can
// change under auto exposure: re-read at every start().
void V4l2Source::refresh_exposure() {
  double e = cfg_.exposure_s;
  if (e == 0 && !v4l2::query_exposure(*dev_, e)) e = 0;
  timing_.exposure_s = e;
}

void V4l2Source::start() {
  if (!dev_) throw std::logic_error("v4l2: start() before open()");
  if (streaming_) return;
  refresh_exposure();
  ring_->allocate(cfg_.buffers);
  if (const int err = dev_->stream_on()) {
    ring_->release();
    v4l2::throw_errno(err, "VIDIOC_STREAMON", cfg_.device);
  }
  sequence_.reset();  // the driver counts from zero again after STREAMON
  streaming_ = true;
}

namespace {

std::string describe(int w, int h, dsp::PixelFormat f) {
  static const char* names[] = {"Mono8", "Mono16", "Rgb8"};
  return std::to_string(w) + "x" + std::to_string(h) + " " + names[static_cast<int>(f)];
}

}  // namespace

void V4l2Source::check_slot(const dsp::ImageView& dst) const {
  const FrameFormat f = format();
  if (!dst.data || dst.width != f.width || dst.height != f.height || dst.format != f.format)
    throw std::invalid_argument("v4l2: frame slot is " + describe(dst.width, dst.height, dst.format) +
                                (dst.data ? "" : " without memory") + ", the camera delivers " +
                                describe(f.width, f.height, f.format) + ": allocate slots from format()");
}

CaptureStatus V4l2Source::capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) {
  using std::chrono::steady_clock;
  if (!streaming_) throw std::logic_error("v4l2: capture() before start()");
  check_slot(dst);
  const auto deadline = steady_clock::now() + timeout;
  // Past the deadline, frames that are already filled may still be drained (a skipped bad
  // frame should not hide a good one behind it), but no more than the ring holds.
  std::size_t drain = ring_->count();
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - steady_clock::now());
    bool ready = false;
    const int err = dev_->wait_readable(static_cast<int>(std::max<std::int64_t>(0, left.count())), ready);
    if (err && err != EINTR) v4l2::throw_errno(err, "poll", cfg_.device);
    if (!err && !ready) return CaptureStatus::Timeout;
    v4l2_buffer b{};
    if (!err && ring_->dequeue(b)) {
      const std::int64_t dequeued_ns = clock_();
      const Delivery d = deliver(b, dst, meta, dequeued_ns);
      ring_->queue(b.index);  // back to the driver at once: the slot holds the copy
      if (d == Delivery::Delivered) return CaptureStatus::Frame;
    }
    if (steady_clock::now() >= deadline && drain-- == 0) return CaptureStatus::Timeout;
  }
}

V4l2Source::Delivery V4l2Source::deliver(const v4l2_buffer& b, const dsp::ImageView& dst, FrameMeta& meta,
                                         std::int64_t dequeued_ns) {
  // Every dequeued frame advances the sequence, so that a skipped one shows as a gap.
  const std::uint64_t seq = sequence_.update(b.sequence);
  stats_.dropped = sequence_.dropped();
  stats_.restarts = sequence_.restarts();
  if (b.flags & V4L2_BUF_FLAG_ERROR) {
    ++stats_.error_frames;
    refused_.fetch_add(1, std::memory_order_relaxed);
    return Delivery::Skipped;
  }
  const auto mem = ring_->data(b.index);
  const std::size_t used = std::min<std::size_t>(b.bytesused, mem.size());
  if (!v4l2::copy_frame(mem.data(), used, negotiated_.bytesperline, negotiated_.layout, dst)) {
    ++stats_.short_frames;
    refused_.fetch_add(1, std::memory_order_relaxed);
    return Delivery::Skipped;
  }
  const v4l2::FirstRowTime t =
      v4l2::first_row_start(b, negotiated_.height, timing_.line_delay_s, timing_.exposure_s, dequeued_ns);
  if (!t.from_driver_clock) ++stats_.estimated_stamps;
  meta.first_row_ns = t.ns;
  meta.sequence = seq;
  meta.exposure_s = timing_.exposure_s;
  ++stats_.frames;
  return Delivery::Delivered;
}

void V4l2Source::stop() {
  if (!streaming_) return;
  streaming_ = false;
  // STREAMOFF returns every buffer; a lost camera fails it, and there is nothing to undo then.
  dev_->stream_off();
  ring_->release();
}

void V4l2Source::close() noexcept {
  if (dev_ && streaming_) stop();
  streaming_ = false;
  ring_.reset();
  dev_.reset();
}

}  // namespace rsd::drivers
