#include "drivers/libcamera_source.hpp"

#include <libcamera/libcamera.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <mutex>
#include <stdexcept>

#include "drivers/libcamera_logic.hpp"
#include "dsp/core/input_limits.hpp"

namespace rsd::drivers {

namespace {

std::int64_t clock_ns(clockid_t id) {
  timespec ts;
  clock_gettime(id, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

// libcamera allows one CameraManager per process (a second is a fatal error that aborts), so
// all sources share one, started on first use and stopped with the last source that uses it.
std::shared_ptr<libcamera::CameraManager> shared_manager() {
  static std::mutex mutex;
  static std::weak_ptr<libcamera::CameraManager> current;
  std::lock_guard lock(mutex);
  if (auto m = current.lock()) return m;
  auto fresh = std::make_unique<libcamera::CameraManager>();
  if (const int ret = fresh->start())
    throw CameraError(std::string("libcamera: the camera manager did not start (") + std::strerror(-ret) + ")");
  std::shared_ptr<libcamera::CameraManager> m(fresh.release(), [](libcamera::CameraManager* p) {
    p->stop();
    delete p;
  });
  current = m;
  return m;
}

// libcamera returns -errno; the V4L2 mapping decides lost (CameraError) vs. a bug.
void check(int ret, std::string_view call, const std::string& id) {
  if (ret < 0) v4l2::throw_errno(-ret, call, "libcamera:" + id);
}

}  // namespace

// Everything libcamera: the camera, its configuration, buffers, mappings and requests.
class LibcameraSource::Live {
 public:
  struct Plane {
    void* base = nullptr;
    std::size_t map_length = 0;
    const std::uint8_t* data = nullptr;
    std::size_t length = 0;
  };

  ~Live();
  void find_camera(const std::string& wanted);
  lc::FormatInfo configure(const LibcameraConfig& cfg, std::vector<std::string>& notes);
  void allocate();
  void start(double fps);
  void requeue(std::uint64_t cookie);
  void stop() noexcept;
  bool deliver(const lc::Completion& c, const dsp::RowTiming& timing, const dsp::ImageView& dst, FrameMeta& meta,
               LibcameraStats& stats);

  std::shared_ptr<libcamera::CameraManager> manager;  // first: destroyed last
  std::shared_ptr<libcamera::Camera> camera;
  std::string id;
  bool acquired = false, connected = false, started = false;
  std::unique_ptr<libcamera::CameraConfiguration> config;
  libcamera::Stream* stream = nullptr;
  unsigned stride = 0;
  v4l2::Layout layout = v4l2::Layout::Grey8;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator;
  std::vector<std::unique_ptr<libcamera::Request>> requests;
  std::vector<Plane> planes;
  lc::CompletionQueue completions;
  lc::ClockResolver clocks;
  v4l2::SequenceTracker sequence;

 private:
  void map_plane(const libcamera::FrameBuffer& fb);
  void on_request_completed(libcamera::Request* r);
  void on_camera_removed(std::shared_ptr<libcamera::Camera> cam);
};

LibcameraSource::Live::~Live() {
  stop();
  if (connected) {
    camera->requestCompleted.disconnect(this);
    manager->cameraRemoved.disconnect(this);
  }
  requests.clear();
  for (const Plane& p : planes) ::munmap(p.base, p.map_length);
  allocator.reset();
  config.reset();
  if (acquired) camera->release();
}

void LibcameraSource::Live::find_camera(const std::string& wanted) {
  std::vector<std::string> ids;
  const auto cams = manager->cameras();
  for (const auto& c : cams) ids.push_back(c->id());
  camera = wanted.empty() ? (cams.empty() ? nullptr : cams.front()) : manager->get(wanted);
  if (!camera) throw CameraError(lc::no_camera_message(wanted, ids));
  id = camera->id();
  check(camera->acquire(), "Camera::acquire", id);
  acquired = true;
}

lc::FormatInfo LibcameraSource::Live::configure(const LibcameraConfig& cfg, std::vector<std::string>& notes) {
  lc::Role role = lc::Role::Auto;
  lc::parse_role(cfg.role, role);
  config = camera->generateConfiguration({lc::stream_role(role)});
  if (!config || config->empty())
    throw std::runtime_error("libcamera camera " + id + " cannot produce a " + lc::role_name(role) + " stream");
  libcamera::StreamConfiguration& sc = config->at(0);
  const auto offered = sc.formats().pixelformats();
  const auto choice = lc::choose_format(cfg.format, offered);
  if (!choice) {
    std::string list;
    for (const auto& f : offered) list += (list.empty() ? "" : ", ") + f.toString();
    throw std::runtime_error("libcamera camera " + id + " offers none of R8, YUYV, BGR888, RGB888 for a " +
                             lc::role_name(role) + " stream (it offers " + (list.empty() ? "nothing" : list) + ")");
  }
  sc.pixelFormat = choice->format;
  sc.size = libcamera::Size(static_cast<unsigned>(cfg.width), static_cast<unsigned>(cfg.height));
  sc.bufferCount = cfg.buffers;
  const std::string asked = sc.toString();
  if (config->validate() == libcamera::CameraConfiguration::Invalid)
    throw std::runtime_error("libcamera camera " + id + " rejects the stream " + asked);
  const lc::FormatInfo* got = lc::format_info(sc.pixelFormat);
  if (!got)
    throw std::runtime_error("libcamera camera " + id + " turned " + asked + " into " + sc.toString() +
                             ", which rsd cannot read");
  if (sc.toString() != asked) notes.push_back("requested " + asked + ", libcamera gives " + sc.toString());
  check(camera->configure(config.get()), "Camera::configure", id);
  stream = sc.stream();
  stride = sc.stride;
  layout = got->layout;
  return *got;
}

void LibcameraSource::Live::allocate() {
  allocator = std::make_unique<libcamera::FrameBufferAllocator>(camera);
  check(allocator->allocate(stream), "FrameBufferAllocator::allocate", id);
  const auto& buffers = allocator->buffers(stream);
  if (buffers.empty()) throw std::runtime_error("libcamera camera " + id + " allocated no buffers");
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    map_plane(*buffers[i]);
    requests.push_back(camera->createRequest(i));
    if (!requests.back()) throw std::runtime_error("libcamera camera " + id + " cannot create requests");
    check(requests.back()->addBuffer(stream, buffers[i].get()), "Request::addBuffer", id);
  }
  camera->requestCompleted.connect(this, &Live::on_request_completed);
  manager->cameraRemoved.connect(this, &Live::on_camera_removed);
  connected = true;
}

// Our formats have one plane; its dmabuf is mapped once, read-only, for the life of the source.
void LibcameraSource::Live::map_plane(const libcamera::FrameBuffer& fb) {
  const libcamera::FrameBuffer::Plane& p = fb.planes().at(0);
  if (p.offset == libcamera::FrameBuffer::Plane::kInvalidOffset)
    throw std::runtime_error("libcamera camera " + id + ": buffer plane without an offset");
  const lc::MapSpan span = lc::page_span(p.offset, p.length, static_cast<std::size_t>(::sysconf(_SC_PAGESIZE)));
  void* base = ::mmap(nullptr, span.map_length, PROT_READ, MAP_SHARED, p.fd.get(), static_cast<off_t>(span.map_offset));
  if (base == MAP_FAILED) v4l2::throw_errno(errno, "mmap", "libcamera:" + id);
  planes.push_back({base, span.map_length, static_cast<const std::uint8_t*>(base) + span.data_offset, p.length});
}

void LibcameraSource::Live::start(double fps) {
  libcamera::ControlList controls(camera->controls());
  if (camera->controls().count(libcamera::controls::FrameDurationLimits.id())) {
    const std::int64_t us = std::llround(1e6 / fps);  // a fixed frame period: min = max
    const std::array<const std::int64_t, 2> limits{us, us};
    controls.set(libcamera::controls::FrameDurationLimits, libcamera::Span<const std::int64_t, 2>(limits));
  }
  check(camera->start(&controls), "Camera::start", id);
  started = true;
  completions.reset();
  sequence.reset();
  for (std::size_t i = 0; i < requests.size(); ++i) requeue(i);
}

void LibcameraSource::Live::requeue(std::uint64_t cookie) {
  libcamera::Request* r = requests.at(cookie).get();
  r->reuse(libcamera::Request::ReuseBuffers);
  completions.queued();  // before queueing: the completion may come back at once
  check(camera->queueRequest(r), "Camera::queueRequest", id);
}

void LibcameraSource::Live::stop() noexcept {
  if (!started) return;
  started = false;
  camera->stop();  // cancels what is in flight; a lost camera fails it, with nothing to undo
  completions.reset();
}

// libcamera's thread: copy out what the capture thread needs, read both clocks first.
void LibcameraSource::Live::on_request_completed(libcamera::Request* r) {
  lc::Completion c;
  c.mono_now_ns = clock_ns(CLOCK_MONOTONIC);
  c.boot_now_ns = clock_ns(CLOCK_BOOTTIME);
  c.cookie = r->cookie();
  c.cancelled = r->status() == libcamera::Request::RequestCancelled;
  if (const libcamera::FrameBuffer* fb = c.cancelled ? nullptr : r->findBuffer(stream)) {
    const libcamera::FrameMetadata& md = fb->metadata();
    c.frame_ok = md.status == libcamera::FrameMetadata::FrameSuccess;
    c.sequence = md.sequence;
    c.buffer_timestamp_ns = md.timestamp;
    if (!md.planes().empty()) c.bytes_used = md.planes()[0].bytesused;
    c.sensor_timestamp_ns = r->metadata().get(libcamera::controls::SensorTimestamp);
    c.exposure_us = r->metadata().get(libcamera::controls::ExposureTime);
  } else {
    c.frame_ok = false;
  }
  completions.push(std::move(c));
}

void LibcameraSource::Live::on_camera_removed(std::shared_ptr<libcamera::Camera> cam) {
  if (cam == camera) completions.lose();
}

// ---- The source ----------------------------------------------------------------------------

void validate(const LibcameraConfig& c) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("libcamera config: " + what); };
  lc::Role role;
  if (!dsp::limits::side_ok(c.width) || !dsp::limits::side_ok(c.height))
    bad(std::string("width/height: expected ") + dsp::limits::kSide.text + ", got " + std::to_string(c.width) + "x" + std::to_string(c.height));
  if (!(std::isfinite(c.fps) && c.fps > 0 && c.fps <= 10000)) bad("fps: expected a rate in (0, 10000]");
  if (c.buffers < 1 || c.buffers > 64) bad("buffers: expected 1..64, got " + std::to_string(c.buffers));
  if (!lc::parse_role(c.role, role)) bad("role: expected auto, viewfinder or raw, got '" + c.role + "'");
  if (!(std::isfinite(c.line_delay_s) && c.line_delay_s >= 0)) bad("line_delay_s: expected >= 0 seconds");
  if (!(std::isfinite(c.exposure_s) && c.exposure_s >= 0)) bad("exposure_s: expected >= 0 seconds");
}

LibcameraSource::LibcameraSource(LibcameraConfig cfg) : cfg_(std::move(cfg)) { validate(cfg_); }
LibcameraSource::~LibcameraSource() = default;

std::string LibcameraSource::name() const {
  return "libcamera:" + (live_ ? live_->id : cfg_.camera_id.empty() ? std::string("first") : cfg_.camera_id);
}

void LibcameraSource::open() {
  live_.reset();
  notes_.clear();
  auto live = std::make_unique<Live>();
  live->manager = shared_manager();
  live->find_camera(cfg_.camera_id);
  const lc::FormatInfo info = live->configure(cfg_, notes_);
  const libcamera::Size size = live->config->at(0).size;
  format_ = {static_cast<int>(size.width), static_cast<int>(size.height), v4l2::output_format(info.layout)};
  if (format_.format != cfg_.format)
    notes_.push_back(std::string("frames are ") + dsp::format_name(format_.format) + ", not the requested " +
                     dsp::format_name(cfg_.format));
  timing_ = dsp::RowTiming::full_frame(format_.height, cfg_.fps, cfg_.readout);
  if (cfg_.line_delay_s > 0) timing_.line_delay_s = cfg_.line_delay_s;
  timing_.exposure_s = cfg_.exposure_s;
  if (timing_.frame_readout_s() > timing_.frame_period_s() * (1 + 1e-9))
    throw std::invalid_argument("libcamera config: line_delay_s x " + std::to_string(format_.height) +
                                " rows exceeds the frame period");
  live->allocate();
  live_ = std::move(live);
}

void LibcameraSource::start() {
  if (!live_) throw std::logic_error("libcamera: start() before open()");
  if (!live_->started) live_->start(cfg_.fps);
}

CaptureStatus LibcameraSource::capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) {
  using std::chrono::steady_clock;
  if (!live_ || !live_->started) throw std::logic_error("libcamera: capture() before start()");
  if (!dst.data || dst.width != format_.width || dst.height != format_.height || dst.format != format_.format)
    throw std::invalid_argument("libcamera: frame slot does not match format(): allocate slots from it");
  const auto deadline = steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::max(std::chrono::milliseconds(0),
                               std::chrono::duration_cast<std::chrono::milliseconds>(deadline - steady_clock::now()));
    lc::Completion c;
    const lc::WaitResult w = live_->completions.pop(left, c);
    if (w == lc::WaitResult::Timeout) return CaptureStatus::Timeout;
    if (w == lc::WaitResult::Lost) throw CameraError("libcamera camera " + live_->id + " was removed (unplugged?)");
    if (live_->deliver(c, timing_, dst, meta, stats_)) return CaptureStatus::Frame;
    if (live_->completions.in_flight() == 0)
      throw CameraError("libcamera camera " + live_->id + " stopped delivering: every request was cancelled");
  }
}

// One completed request: the frame copied into the slot and stamped, or skipped; either
// way the request goes back to the camera unless it was cancelled.
bool LibcameraSource::Live::deliver(const lc::Completion& c, const dsp::RowTiming& timing, const dsp::ImageView& dst,
                                    FrameMeta& meta, LibcameraStats& stats) {
  const lc::Disposition d = lc::dispose(c);
  if (d == lc::Disposition::Retire) return false;
  const std::uint64_t seq = sequence.update(c.sequence);  // a skipped frame shows as a gap
  stats.dropped = sequence.dropped();
  bool ok = d == lc::Disposition::Deliver;
  if (!ok) ++stats.failed_frames;
  const Plane& p = planes.at(c.cookie);
  if (ok && !v4l2::copy_frame(p.data, std::min(c.bytes_used, p.length), stride, layout, dst)) {
    ++stats.short_frames;
    ok = false;
  }
  if (ok) {
    const double exposure = lc::exposure_seconds(c.exposure_us, timing.exposure_s);
    const lc::FirstRowStamp t = lc::first_row_stamp(c, clocks, timing.height, timing.line_delay_s, exposure);
    if (t.origin != lc::StampOrigin::SensorTimestamp) ++stats.fallback_stamps;
    meta.first_row_ns = t.ns;
    meta.sequence = seq;
    meta.exposure_s = exposure;
    ++stats.frames;
  }
  requeue(c.cookie);
  return ok;
}

void LibcameraSource::stop() {
  if (live_) live_->stop();
}

}  // namespace rsd::drivers
