#include "drivers/aravis_source.hpp"

#include "dsp/core/image_planes.hpp"
#include <arv.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <vector>

#include "drivers/aravis_device.hpp"

namespace rsd::drivers {

namespace {

using Clock = std::chrono::steady_clock;
constexpr uint32_t kGvbsVersionRegister = 0x0000;  // every GigE Vision device answers it

}  // namespace

using namespace aravis;

struct AravisSource::Impl {
  AravisConfig cfg;
  const FormatName* pixel = nullptr;
  GPtr<ArvDevice> device;
  GPtr<ArvCamera> camera;
  GPtr<ArvStream> stream;
  bool gige = false, started = false, lost = false, fake_filled = false;
  size_t payload = 0;  // bytes allocated for each buffer
  std::atomic<bool> control_lost{false};
  FrameFormat fmt;
  dsp::RowTiming timing;
  ReceiptModel receipt;
  std::optional<CameraClockMapper> mapper;
  FrameCounter counter;
  Clock::time_point last_frame;
  AravisStats stats;
  std::atomic<uint64_t> refused{0};  // stats.incomplete + stats.mismatched, for any thread

  explicit Impl(AravisConfig c) : cfg(std::move(c)) {}
  ~Impl() { close(); }

  void open();
  void close();
  void start();
  void stop();
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout);

 private:
  void open_and_configure();
  void fail(GErr& err, const std::string& what) const;
  void configure_pixel_format();
  void configure_region();
  void check_bounds(const char* what, int value, void (*bounds)(ArvCamera*, gint*, gint*, GError**)) const;
  double configure_frame_rate();
  double configure_exposure();
  void configure_timing(double fps, double exposure_s);
  void create_stream();
  void install_fake_fill();
  void throw_if_lost();
  void check_alive();
  const uint8_t* image_bytes(ArvBuffer* b, size_t& size) const;
  bool usable(ArvBuffer* b);
  void copy_image(ArvBuffer* b, const dsp::ImageView& dst) const;
  void stamp(ArvBuffer* b, FrameMeta& meta);
  void drain();
  static void on_control_lost(ArvDevice*, gpointer self);
  static void fake_fill(ArvBuffer* b, void* self, guint32, guint32, ArvPixelFormat);
};

// Throws for a failed Aravis call: CameraError when the camera went away, else the camera
// cannot do what we ask.
void AravisSource::Impl::fail(GErr& err, const std::string& what) const {
  const std::string msg = "aravis " + cfg.camera + ": " + what + ": " + err.message();
  if (err.transport()) throw CameraError(msg);
  throw std::runtime_error(msg);
}

void AravisSource::Impl::open() {
  if (camera) throw std::logic_error("aravis " + cfg.camera + ": open() called twice");
  try {
    open_and_configure();
  } catch (...) {
    close();  // a failed open() leaves nothing behind; open() may be tried again
    throw;
  }
}

void AravisSource::Impl::open_and_configure() {
  gige = !is_fake(cfg.camera);
  device = open_device(cfg.camera);
  g_signal_connect(device.get(), "control-lost", as_gcallback(&Impl::on_control_lost), this);
  GErr err;
  camera.reset(arv_camera_new_with_device(device.get(), err.out()));
  if (!camera) fail(err, "no camera on the device");
  configure_pixel_format();
  configure_region();
  const double fps = configure_frame_rate();
  configure_timing(fps, configure_exposure());
  // Before the stream: Aravis' fake fills frames from the moment its stream has buffers, and a
  // frame filled with its own ramp before ours was installed was delivered as the first frame
  // (AravisFake.Rgb8ArrivesExactly, 1 run in 55 under ASan beside four busy loops).
  if (!gige && cfg.fake_fill) install_fake_fill();
  create_stream();
  mapper.emplace(cfg.clock);
}

void AravisSource::Impl::configure_pixel_format() {
  GErr err;
  guint n = 0;
  const char** offered = arv_camera_dup_available_pixel_formats_as_strings(camera.get(), &n, err.out());
  if (!offered) fail(err, "reading the pixel formats");
  std::string list;
  const char* chosen = nullptr;
  for (guint i = 0; i < n; ++i) {
    list += (i ? ", " : "") + std::string(offered[i]);
    for (const char* name : pixel->sfnc)
      if (!chosen && name && std::strcmp(offered[i], name) == 0) chosen = name;
  }
  const std::string choice = chosen ? chosen : "";
  g_free(offered);
  if (choice.empty())
    throw std::runtime_error("aravis " + cfg.camera + ": pixel format " + cfg.pixel_format +
                             " not offered (the camera offers " + list + ")");
  arv_camera_set_pixel_format_from_string(camera.get(), choice.c_str(), err.out());
  if (err) fail(err, "setting pixel format " + choice);
  const ArvPixelFormat now = arv_camera_get_pixel_format(camera.get(), err.out());
  if (err) fail(err, "reading the pixel format back");
  if (now != pixel->arv) throw std::runtime_error("aravis " + cfg.camera + ": the camera did not take pixel format " + choice);
  fmt.format = pixel->dsp;
}

void AravisSource::Impl::configure_region() {
  GErr err;
  gint x = 0, y = 0, w = 0, h = 0;
  arv_camera_get_region(camera.get(), &x, &y, &w, &h, err.out());
  if (err) fail(err, "reading the region");
  const int want_w = cfg.width ? cfg.width : w, want_h = cfg.height ? cfg.height : h;
  check_bounds("width", want_w, &arv_camera_get_width_bounds);
  check_bounds("height", want_h, &arv_camera_get_height_bounds);
  arv_camera_set_region(camera.get(), cfg.offset_x, cfg.offset_y, want_w, want_h, err.out());
  if (err) fail(err, "setting the region " + std::to_string(want_w) + "x" + std::to_string(want_h));
  arv_camera_get_region(camera.get(), &x, &y, &w, &h, err.out());
  if (err) fail(err, "reading the region back");
  if (w != want_w || h != want_h || x != cfg.offset_x || y != cfg.offset_y)
    throw std::runtime_error("aravis " + cfg.camera + ": asked for " + std::to_string(want_w) + "x" +
                             std::to_string(want_h) + "+" + std::to_string(cfg.offset_x) + "+" +
                             std::to_string(cfg.offset_y) + ", the camera set " + std::to_string(w) + "x" +
                             std::to_string(h) + "+" + std::to_string(x) + "+" + std::to_string(y));
  fmt.width = w;
  fmt.height = h;
}

// Some cameras (Aravis' fake among them) take any size and fail later: ask first.
void AravisSource::Impl::check_bounds(const char* what, int value,
                                      void (*bounds)(ArvCamera*, gint*, gint*, GError**)) const {
  GErr err;
  gint lo = 0, hi = 0;
  bounds(camera.get(), &lo, &hi, err.out());
  if (err) fail(err, std::string("reading the ") + what + " bounds");
  if (value < lo || value > hi)
    throw std::runtime_error("aravis " + cfg.camera + ": " + what + " " + std::to_string(value) +
                             " is outside the camera's " + std::to_string(lo) + ".." + std::to_string(hi));
}

// The frame rate the camera runs at: set when asked, read back; a camera that cannot tell
// (external trigger) runs at the configured rate.
double AravisSource::Impl::configure_frame_rate() {
  GErr err;
  const bool available = arv_camera_is_frame_rate_available(camera.get(), err.out());
  if (err) fail(err, "asking for the frame rate");
  if (!available) {
    if (cfg.frame_rate_hz > 0) return cfg.frame_rate_hz;
    throw std::runtime_error("aravis " + cfg.camera + ": the camera has no frame rate to read; set frame_rate_hz");
  }
  if (cfg.frame_rate_hz > 0) {
    arv_camera_set_frame_rate(camera.get(), cfg.frame_rate_hz, err.out());
    if (err) fail(err, "setting the frame rate to " + std::to_string(cfg.frame_rate_hz) + " Hz");
  }
  const double fps = arv_camera_get_frame_rate(camera.get(), err.out());
  if (err) fail(err, "reading the frame rate");
  if (cfg.frame_rate_hz > 0 && std::abs(fps - cfg.frame_rate_hz) > 0.01 * cfg.frame_rate_hz)
    throw std::runtime_error("aravis " + cfg.camera + ": asked for " + std::to_string(cfg.frame_rate_hz) +
                             " Hz, the camera runs at " + std::to_string(fps) + " Hz");
  if (!(fps > 0)) throw std::runtime_error("aravis " + cfg.camera + ": the camera reports no frame rate");
  return fps;
}

double AravisSource::Impl::configure_exposure() {
  GErr err;
  const bool available = arv_camera_is_exposure_time_available(camera.get(), err.out());
  if (err) fail(err, "asking for the exposure time");
  if (!available) return cfg.exposure_s;
  if (cfg.exposure_s > 0) {
    // A fixed exposure: auto exposure would change it under the row timing.
    if (arv_camera_is_exposure_auto_available(camera.get(), nullptr))
      arv_camera_set_exposure_time_auto(camera.get(), ARV_AUTO_OFF, err.out());
    if (err) fail(err, "turning auto exposure off");
    arv_camera_set_exposure_time(camera.get(), cfg.exposure_s * 1e6, err.out());
    if (err) fail(err, "setting the exposure time");
  }
  const double us = arv_camera_get_exposure_time(camera.get(), err.out());
  if (err) fail(err, "reading the exposure time");
  if (cfg.exposure_s > 0 && std::abs(us * 1e-6 - cfg.exposure_s) > 0.01 * cfg.exposure_s + 1e-6)
    throw std::runtime_error("aravis " + cfg.camera + ": asked for exposure " + std::to_string(cfg.exposure_s) +
                             " s, the camera set " + std::to_string(us * 1e-6) + " s");
  return us * 1e-6;
}

void AravisSource::Impl::configure_timing(double fps, double exposure_s) {
  timing = dsp::RowTiming::full_frame(fmt.height, fps, cfg.readout);
  if (cfg.line_delay_s > 0) timing.line_delay_s = cfg.line_delay_s;
  timing.exposure_s = exposure_s;
  if (timing.frame_readout_s() > timing.frame_period_s() * (1 + 1e-9))
    throw std::runtime_error("aravis " + cfg.camera + ": line delay x height (" +
                             std::to_string(timing.frame_readout_s()) + " s) exceeds the frame period (" +
                             std::to_string(timing.frame_period_s()) + " s)");
  receipt.stamp = cfg.stamp;
  receipt.exposure_s = exposure_s;
  receipt.leader_delay_s = cfg.leader_delay_s;
}

void AravisSource::Impl::create_stream() {
  GErr err;
  if (gige) {
    // Jumbo packets where the path takes them; a camera that cannot test keeps its size.
    arv_camera_gv_auto_packet_size(camera.get(), nullptr);
  }
  stream.reset(arv_camera_create_stream(camera.get(), nullptr, nullptr, err.out()));
  if (!stream) fail(err, "creating the stream");
  if (ARV_IS_GV_STREAM(stream.get()))
    g_object_set(stream.get(), "socket-buffer", ARV_GV_STREAM_SOCKET_BUFFER_AUTO, nullptr);
  payload = arv_camera_get_payload(camera.get(), err.out());
  if (err) fail(err, "reading the payload size");
  if (payload < fmt.bytes())
    throw std::runtime_error("aravis " + cfg.camera + ": payload " + std::to_string(payload) + " bytes < image " +
                             std::to_string(fmt.bytes()) + " bytes");
  for (int i = 0; i < cfg.buffers; ++i) arv_stream_push_buffer(stream.get(), arv_buffer_new_allocate(payload));
}

void AravisSource::Impl::install_fake_fill() {
  ArvFakeCamera* fake = arv_fake_device_get_fake_camera(ARV_FAKE_DEVICE(device.get()));
  arv_fake_camera_set_fill_pattern(fake, &Impl::fake_fill, this);
  fake_filled = true;
}

// Aravis' stream thread, filling a fake frame: hand the caller a view of it.
void AravisSource::Impl::fake_fill(ArvBuffer* b, void* self, guint32, guint32, ArvPixelFormat) {
  auto* impl = static_cast<Impl*>(self);
  auto* data = static_cast<uint8_t*>(const_cast<void*>(arv_buffer_get_data(b, nullptr)));
  const FrameFormat& f = impl->fmt;
  if (!data) return;  // one of our buffers: payload >= f.bytes() was checked at open
  const dsp::ImageView view{data, f.width, f.height,
                            static_cast<std::ptrdiff_t>(dsp::row_bytes(f.format, f.width)), f.format};
  impl->cfg.fake_fill(view, arv_buffer_get_frame_id(b), checked_stamp(arv_buffer_get_timestamp(b)));
}

// Aravis' heartbeat thread: the camera stopped answering the control channel.
void AravisSource::Impl::on_control_lost(ArvDevice*, gpointer self) {
  static_cast<Impl*>(self)->control_lost = true;
}

void AravisSource::Impl::start() {
  if (!camera) throw std::logic_error("aravis " + cfg.camera + ": start() before open()");
  throw_if_lost();
  if (started) return;
  GErr err;
  arv_camera_set_acquisition_mode(camera.get(), ARV_ACQUISITION_MODE_CONTINUOUS, err.out());
  if (err) fail(err, "setting continuous acquisition");
  arv_camera_start_acquisition(camera.get(), err.out());
  if (err) fail(err, "starting acquisition");
  started = true;
  last_frame = Clock::now();
}

void AravisSource::Impl::stop() {
  if (!started) return;
  started = false;
  if (!lost && !control_lost) {
    GErr err;
    arv_camera_stop_acquisition(camera.get(), err.out());
    lost = err.transport();  // stop() reports nothing; the next start() will
  }
  drain();
}

// Frames that arrived after the last capture() go back to the stream, not to the next start.
void AravisSource::Impl::drain() {
  while (ArvBuffer* b = arv_stream_try_pop_buffer(stream.get())) arv_stream_push_buffer(stream.get(), b);
}

void AravisSource::Impl::close() {
  if (stream) stop();
  if (device) g_signal_handlers_disconnect_by_data(device.get(), this);
  stream.reset();  // joins the stream thread before the camera goes
  camera.reset();
  device.reset();
  fake_filled = false;
  mapper.reset();
}

void AravisSource::Impl::throw_if_lost() {
  if (control_lost && !lost) {
    lost = true;
    throw CameraError("aravis: camera at " + cfg.camera + " lost: it stopped answering the control channel");
  }
  if (lost) throw CameraError("aravis: camera at " + cfg.camera + " was lost");
}

// No frame for a while: a camera that answers a register read is there, only quiet.
void AravisSource::Impl::check_alive() {
  throw_if_lost();
  if (!gige || Clock::now() - last_frame < cfg.lost_after) return;
  GErr err;
  guint32 value = 0;
  if (!arv_device_read_register(device.get(), kGvbsVersionRegister, &value, err.out())) {
    lost = true;
    throw CameraError("aravis: camera at " + cfg.camera + " lost: no frame for " +
                      std::to_string(cfg.lost_after.count()) + " ms and no answer (" + err.message() + ")");
  }
  last_frame = Clock::now();
}

// The image in a buffer and its size. Aravis 0.8's fake camera reports the size its own
// pattern wrote, 0 after a custom one; ours wrote the whole image into our buffer.
const uint8_t* AravisSource::Impl::image_bytes(ArvBuffer* b, size_t& size) const {
  const auto* data = static_cast<const uint8_t*>(arv_buffer_get_image_data(b, &size));
  if (fake_filled) size = payload;
  return data;
}

bool AravisSource::Impl::usable(ArvBuffer* b) {
  if (arv_buffer_get_status(b) != ARV_BUFFER_STATUS_SUCCESS) {
    ++stats.incomplete;
    refused.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  size_t size = 0;
  const uint8_t* data = image_bytes(b, size);
  gint pad_x = 0, pad_y = 0;
  arv_buffer_get_image_padding(b, &pad_x, &pad_y);
  const size_t need = dsp::buffer_bytes(fmt.format, fmt.width, fmt.height, dsp::row_bytes(fmt.format, fmt.width) + pad_x);
  if (!data || size < need || arv_buffer_get_image_width(b) != fmt.width ||
      arv_buffer_get_image_height(b) != fmt.height || arv_buffer_get_image_pixel_format(b) != pixel->arv) {
    ++stats.mismatched;
    refused.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  return true;
}

void AravisSource::Impl::copy_image(ArvBuffer* b, const dsp::ImageView& dst) const {
  size_t size = 0;
  const uint8_t* src = image_bytes(b, size);
  gint pad_x = 0, pad_y = 0;
  arv_buffer_get_image_padding(b, &pad_x, &pad_y);
  const auto stride = static_cast<std::ptrdiff_t>(dsp::row_bytes(fmt.format, fmt.width) + pad_x);
  dsp::copy_image(src, stride, dst);
}

void AravisSource::Impl::stamp(ArvBuffer* b, FrameMeta& meta) {
  const int64_t receipt_ns = host_stamp_to_monotonic(checked_stamp(arv_buffer_get_system_timestamp(b)),
                                                     read_host_clocks());
  const int64_t bound = receipt_ns - receipt.receipt_delay_ns();
  const int64_t camera_ns = checked_stamp(arv_buffer_get_timestamp(b));
  const int64_t stamped = cfg.use_camera_clock && camera_ns > 0 ? mapper->add(camera_ns, bound) : bound;
  meta.first_row_ns = receipt.first_row_ns(stamped);
  meta.sequence = counter.next(arv_buffer_get_frame_id(b));
  meta.exposure_s = timing.exposure_s;
}

CaptureStatus AravisSource::Impl::capture(const dsp::ImageView& dst, FrameMeta& meta,
                                          std::chrono::milliseconds timeout) {
  if (!started) throw std::logic_error("aravis " + cfg.camera + ": capture() before start()");
  if (!dst.data || dst.width != fmt.width || dst.height != fmt.height || dst.format != fmt.format)
    throw std::invalid_argument("aravis " + cfg.camera + ": capture() into a slot not of format()");
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    throw_if_lost();
    const auto left = std::chrono::duration_cast<std::chrono::microseconds>(deadline - Clock::now());
    ArvBuffer* b = left.count() > 0 ? arv_stream_timeout_pop_buffer(stream.get(), left.count())
                                    : arv_stream_try_pop_buffer(stream.get());
    if (!b) {
      check_alive();
      return CaptureStatus::Timeout;
    }
    const bool ok = usable(b);
    if (ok) {
      copy_image(b, dst);
      stamp(b, meta);
    }
    arv_stream_push_buffer(stream.get(), b);
    if (ok) {
      last_frame = Clock::now();
      ++stats.frames;
      return CaptureStatus::Frame;
    }
  }
}

AravisSource::AravisSource(AravisConfig cfg) : impl_(std::make_unique<Impl>(std::move(cfg))) {
  const AravisConfig& c = impl_->cfg;
  check_camera_id(c.camera);
  impl_->pixel = find_format(c.pixel_format);
  if (!impl_->pixel)
    throw std::invalid_argument("aravis: pixel_format '" + c.pixel_format + "': rsd takes Mono8, Mono16 or RGB8");
  if (c.width < 0 || c.height < 0 || c.offset_x < 0 || c.offset_y < 0)
    throw std::invalid_argument("aravis: width, height and offsets must not be negative");
  if (c.frame_rate_hz < 0 || c.exposure_s < 0 || c.line_delay_s < 0)
    throw std::invalid_argument("aravis: frame_rate_hz, exposure_s and line_delay_s must not be negative");
  if (c.buffers < 2) throw std::invalid_argument("aravis: buffers must be at least 2");
  if (c.lost_after.count() <= 0) throw std::invalid_argument("aravis: lost_after must be positive");
}

AravisSource::~AravisSource() = default;

std::string AravisSource::name() const { return "aravis " + impl_->cfg.camera; }
void AravisSource::open() { impl_->open(); }
FrameFormat AravisSource::format() const { return impl_->fmt; }
dsp::RowTiming AravisSource::timing() const { return impl_->timing; }
void AravisSource::start() { impl_->start(); }
void AravisSource::stop() { impl_->stop(); }

CaptureStatus AravisSource::capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) {
  return impl_->capture(dst, meta, timeout);
}

uint64_t AravisSource::refused() const { return impl_ ? impl_->refused.load(std::memory_order_relaxed) : 0; }

AravisStats AravisSource::stats() const {
  AravisStats s = impl_->stats;
  if (impl_->stream) {
    guint64 completed = 0, failures = 0, underruns = 0;
    arv_stream_get_statistics(impl_->stream.get(), &completed, &failures, &underruns);
    s.underruns = underruns;
  }
  if (impl_->mapper) {
    s.clock_resets = impl_->mapper->resets();
    s.clock_drift = impl_->mapper->drift();
  }
  s.counter_restarts = impl_->counter.restarts();
  return s;
}

}  // namespace rsd::drivers
