#include "drivers/v4l2_logic.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "dsp/core/image_planes.hpp"
#include "dsp/core/stamp.hpp"

namespace rsd::drivers::v4l2 {

// ---- Pixel layouts -------------------------------------------------------------------------

namespace {

void check_destination(Layout l, const dsp::ImageView& dst) {
  if (!dst.data || dst.width <= 0 || dst.height <= 0)
    throw std::invalid_argument("frame copy: destination slot has no pixels");
  if (dst.format != output_format(l))
    throw std::invalid_argument("frame copy: destination slot has the wrong pixel format");
  if (dst.stride < static_cast<std::ptrdiff_t>(dsp::row_bytes(dst.format, dst.width)))
    throw std::invalid_argument("frame copy: destination stride shorter than a row");
}

}  // namespace

bool copy_frame(const std::uint8_t* src, std::size_t src_len, std::size_t src_stride, Layout l,
                const dsp::ImageView& dst) {
  check_destination(l, dst);
  const std::size_t row_bytes = dsp::row_bytes(l.format, dst.width);
  if (src_stride < row_bytes) src_stride = row_bytes;  // a driver that reports 0 means packed
  if (l.format == dsp::PixelFormat::I420 && src_stride % 2) return false;  // chroma rows at stride / 2
  if (!src || src_len < dsp::buffer_bytes(l.format, dst.width, dst.height, src_stride)) return false;
  const auto stride = static_cast<std::ptrdiff_t>(src_stride);
  if (!l.bgr) return dsp::copy_image(src, stride, dst), true;
  for (int y = 0; y < dst.height; ++y) {
    const std::uint8_t* s = src + y * stride;
    std::uint8_t* d = dst.row(y);
    for (int x = 0; x < dst.width; ++x, s += 3, d += 3) d[0] = s[2], d[1] = s[1], d[2] = s[0];
  }
  return true;
}

// ---- V4L2 pixel formats --------------------------------------------------------------------

namespace {

using PF = dsp::PixelFormat;

constexpr std::array<PixelInfo, 15> kPixels{{
    {V4L2_PIX_FMT_GREY, "GREY", Layout::Grey8},
    {V4L2_PIX_FMT_Y16, "Y16", Layout::Grey16},
    {V4L2_PIX_FMT_YUYV, "YUYV", native(PF::Yuyv)},
    {V4L2_PIX_FMT_RGB24, "RGB24", Layout::Rgb24},
    {V4L2_PIX_FMT_NV12, "NV12", native(PF::Nv12)},
    {V4L2_PIX_FMT_YUV420, "YU12", native(PF::I420)},
    {V4L2_PIX_FMT_SRGGB8, "RGGB", native(PF::BayerRggb8)},
    {V4L2_PIX_FMT_SBGGR8, "BA81", native(PF::BayerBggr8)},
    {V4L2_PIX_FMT_SGRBG8, "GRBG", native(PF::BayerGrbg8)},
    {V4L2_PIX_FMT_SGBRG8, "GBRG", native(PF::BayerGbrg8)},
    {V4L2_PIX_FMT_SRGGB16, "RG16", native(PF::BayerRggb16)},
    {V4L2_PIX_FMT_SBGGR16, "BYR2", native(PF::BayerBggr16)},
    {V4L2_PIX_FMT_SGRBG16, "GR16", native(PF::BayerGrbg16)},
    {V4L2_PIX_FMT_SGBRG16, "GB16", native(PF::BayerGbrg16)},
    {V4L2_PIX_FMT_BGR24, "BGR3", Layout::Bgr24},
}};

// For each request, the formats to fall back to, best first: the request itself, then (for
// the four classic ones) grey requests prefer YUYV next because its luma is the same 8 bits, a
// 16-bit request prefers 8-bit grey over colour, an RGB request prefers YUYV (a colour camera)
// over a grey one; then the rest of the table, in its order.
std::vector<std::uint32_t> preference(std::uint32_t requested) {
  std::vector<std::uint32_t> order;
  switch (requested) {
    case V4L2_PIX_FMT_Y16: order = {V4L2_PIX_FMT_Y16, V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_RGB24}; break;
    case V4L2_PIX_FMT_YUYV: order = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_RGB24, V4L2_PIX_FMT_Y16}; break;
    case V4L2_PIX_FMT_RGB24: order = {V4L2_PIX_FMT_RGB24, V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_Y16}; break;
    case V4L2_PIX_FMT_GREY: order = {V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_Y16, V4L2_PIX_FMT_RGB24}; break;
    default: order = {requested};
  }
  for (const PixelInfo& p : kPixels)
    if (std::find(order.begin(), order.end(), p.fourcc) == order.end()) order.push_back(p.fourcc);
  return order;
}

}  // namespace

std::string pixel_format_names() {
  std::string s;
  for (const PixelInfo& p : kPixels) s += (s.empty() ? "" : ", ") + std::string(p.name);
  return s;
}

const PixelInfo* pixel_info(std::uint32_t fourcc) {
  for (const auto& p : kPixels)
    if (p.fourcc == fourcc) return &p;
  return nullptr;
}

bool parse_pixel_format(std::string_view name, std::uint32_t& fourcc) {
  for (const auto& p : kPixels)
    if (name == p.name) {
      fourcc = p.fourcc;
      return true;
    }
  return false;
}

std::string fourcc_name(std::uint32_t fourcc) {
  std::string s(4, '?');
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
    if (c >= 0x20 && c < 0x7f) s[i] = c;
  }
  return s;
}

std::uint32_t choose_pixel_format(std::uint32_t requested, const std::vector<std::uint32_t>& offered) {
  for (std::uint32_t f : preference(requested))
    if (std::find(offered.begin(), offered.end(), f) != offered.end()) return f;
  return 0;
}

namespace {

// Clamps v into [lo, hi] and rounds it to the nearest lo + k * step.
int snap(int v, std::uint32_t lo, std::uint32_t hi, std::uint32_t step) {
  const double c = std::clamp<double>(v, lo, hi);
  if (step == 0) return static_cast<int>(c);
  const long k = std::lround((c - lo) / step);
  return static_cast<int>(std::min<long>(lo + k * static_cast<long>(step), hi));
}

}  // namespace

Size choose_frame_size(Size req, const std::vector<v4l2_frmsizeenum>& sizes) {
  if (sizes.empty()) return req;
  if (sizes.front().type != V4L2_FRMSIZE_TYPE_DISCRETE) {
    const auto& s = sizes.front().stepwise;
    return {snap(req.width, s.min_width, s.max_width, s.step_width),
            snap(req.height, s.min_height, s.max_height, s.step_height)};
  }
  Size best{};
  long best_cost = -1;
  for (const auto& e : sizes) {
    const int w = static_cast<int>(e.discrete.width), h = static_cast<int>(e.discrete.height);
    const long cost = std::labs(long{w} - req.width) + std::labs(long{h} - req.height);
    // Ties go to the larger size: cropping in software is possible, upscaling is not.
    if (best_cost < 0 || cost < best_cost || (cost == best_cost && w * h > best.width * best.height)) {
      best = {w, h};
      best_cost = cost;
    }
  }
  return best;
}

// ---- Negotiation ---------------------------------------------------------------------------

void check_capabilities(const v4l2_capability& cap, const std::string& path) {
  // device_caps describes this node; capabilities the whole device (all its nodes).
  const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
  const bool capture = caps & V4L2_CAP_VIDEO_CAPTURE, streaming = caps & V4L2_CAP_STREAMING;
  if (capture && streaming) return;
  std::ostringstream msg;
  msg << path << " (" << reinterpret_cast<const char*>(cap.card) << ", driver "
      << reinterpret_cast<const char*>(cap.driver) << ") cannot "
      << (capture ? "stream (no V4L2_CAP_STREAMING)"
                  : "capture video (no V4L2_CAP_VIDEO_CAPTURE); a UVC camera's second node is metadata "
                    "only: try the neighbouring /dev/videoN");
  throw std::runtime_error(msg.str());
}

namespace {

std::vector<std::uint32_t> enum_formats(V4l2Device& dev, const std::string& path) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = 0; i < 256; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    const int err = dev.enum_format(d);
    if (err == EINVAL) break;  // the end of the list
    if (err) throw_errno(err, "VIDIOC_ENUM_FMT", path);
    out.push_back(d.pixelformat);
  }
  return out;
}

std::vector<v4l2_frmsizeenum> enum_sizes(V4l2Device& dev, std::uint32_t fourcc, const std::string& path) {
  std::vector<v4l2_frmsizeenum> out;
  for (std::uint32_t i = 0; i < 1024; ++i) {
    v4l2_frmsizeenum s{};
    s.index = i;
    s.pixel_format = fourcc;
    const int err = dev.enum_frame_size(s);
    if (err == EINVAL || err == ENOTTY) break;  // the end, or a driver that cannot enumerate
    if (err) throw_errno(err, "VIDIOC_ENUM_FRAMESIZES", path);
    out.push_back(s);
    if (s.type != V4L2_FRMSIZE_TYPE_DISCRETE) break;  // one stepwise range describes all
  }
  return out;
}

std::string offered_list(const std::vector<std::uint32_t>& offered) {
  std::string s;
  for (std::uint32_t f : offered) s += (s.empty() ? "" : ", ") + fourcc_name(f);
  return s.empty() ? "nothing" : s;
}

void apply_format(V4l2Device& dev, std::uint32_t fourcc, Size size, Negotiated& n, const std::string& path) {
  v4l2_format f{};
  f.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  f.fmt.pix.width = static_cast<std::uint32_t>(size.width);
  f.fmt.pix.height = static_cast<std::uint32_t>(size.height);
  f.fmt.pix.pixelformat = fourcc;
  f.fmt.pix.field = V4L2_FIELD_NONE;
  if (const int err = dev.set_format(f)) throw_errno(err, "VIDIOC_S_FMT", path);
  const PixelInfo* info = pixel_info(f.fmt.pix.pixelformat);
  if (!info || f.fmt.pix.width == 0 || f.fmt.pix.height == 0)
    throw std::runtime_error(path + ": driver answered VIDIOC_S_FMT with " + std::to_string(f.fmt.pix.width) +
                             "x" + std::to_string(f.fmt.pix.height) + " " + fourcc_name(f.fmt.pix.pixelformat) +
                             ", which rsd cannot read");
  n.width = static_cast<int>(f.fmt.pix.width);
  n.height = static_cast<int>(f.fmt.pix.height);
  n.fourcc = f.fmt.pix.pixelformat;
  n.layout = info->layout;
  n.bytesperline = f.fmt.pix.bytesperline;
  n.sizeimage = f.fmt.pix.sizeimage;
  if (f.fmt.pix.field != V4L2_FIELD_NONE && f.fmt.pix.field != V4L2_FIELD_ANY)
    n.notes.push_back("driver delivers field order " + std::to_string(f.fmt.pix.field) +
                      " (interlaced?); rows are treated as progressive");
}

// S_PARM where the driver supports it (V4L2_CAP_TIMEPERFRAME), else G_PARM for what it runs at.
void apply_frame_rate(V4l2Device& dev, double fps, Negotiated& n, const std::string& path) {
  v4l2_streamparm p{};
  p.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  const int gerr = dev.get_parm(p);
  if (gerr && camera_lost(gerr)) throw_errno(gerr, "VIDIOC_G_PARM", path);
  if (!gerr && (p.parm.capture.capability & V4L2_CAP_TIMEPERFRAME)) {
    const v4l2_streamparm current = p;
    p.parm.capture.timeperframe = {1000, static_cast<std::uint32_t>(std::lround(fps * 1000))};
    if (const int err = dev.set_parm(p)) {
      // A refused rate is not fatal: the camera still streams, at the rate it had.
      if (camera_lost(err)) throw_errno(err, "VIDIOC_S_PARM", path);
      n.notes.push_back(std::string("driver refused the frame rate (VIDIOC_S_PARM: ") + std::strerror(err) + ")");
      p = current;
    }
  }
  const auto& tpf = p.parm.capture.timeperframe;
  n.fps_known = !gerr && tpf.numerator > 0 && tpf.denominator > 0;
  n.fps = n.fps_known ? static_cast<double>(tpf.denominator) / tpf.numerator : fps;
  if (!n.fps_known) n.notes.push_back("driver does not report its frame rate; assuming the requested one");
}

std::string describe(int w, int h, std::uint32_t fourcc, double fps) {
  std::ostringstream s;
  s << w << "x" << h << " " << fourcc_name(fourcc) << " at " << fps << " fps";
  return s.str();
}

void note_differences(const FormatRequest& req, Negotiated& n) {
  const bool same = n.width == req.width && n.height == req.height && n.fourcc == req.fourcc &&
                    std::abs(n.fps - req.fps) <= 1e-3 * req.fps;
  if (!same)
    n.notes.push_back("requested " + describe(req.width, req.height, req.fourcc, req.fps) + ", driver gives " +
                      describe(n.width, n.height, n.fourcc, n.fps));
  const auto row = static_cast<std::uint32_t>(dsp::row_bytes(n.layout.format, n.width));
  if (n.bytesperline < row) {
    if (n.bytesperline != 0) n.notes.push_back("driver reports bytesperline below a row; assuming packed rows");
    n.bytesperline = row;
  }
}

}  // namespace

Negotiated negotiate(V4l2Device& dev, const FormatRequest& req, const std::string& path) {
  const std::vector<std::uint32_t> offered = enum_formats(dev, path);
  const std::uint32_t fourcc = choose_pixel_format(req.fourcc, offered);
  if (fourcc == 0)
    throw std::runtime_error(path + " offers none of " + pixel_format_names() + " (it offers " + offered_list(offered) + ")");
  const Size size = choose_frame_size({req.width, req.height}, enum_sizes(dev, fourcc, path));
  Negotiated n;
  apply_format(dev, fourcc, size, n, path);
  apply_frame_rate(dev, req.fps, n, path);
  note_differences(req, n);
  return n;
}

bool query_exposure(V4l2Device& dev, double& exposure_s) {
  v4l2_control c{};
  c.id = V4L2_CID_EXPOSURE_ABSOLUTE;
  if (dev.get_control(c) != 0 || c.value <= 0) return false;
  exposure_s = c.value * 100e-6;  // the control counts 100 us units
  return true;
}

// ---- Buffer bookkeeping --------------------------------------------------------------------

void BufferRing::allocate(unsigned count) {
  release();
  v4l2_requestbuffers req{};
  req.count = count;
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (const int err = dev_.request_buffers(req)) throw_errno(err, "VIDIOC_REQBUFS", path_);
  if (req.count == 0) throw std::runtime_error(path_ + ": driver granted no mmap buffers");
  buffers_.resize(req.count);
  try {
    for (std::uint32_t i = 0; i < req.count; ++i) map_one(i);
    for (std::uint32_t i = 0; i < req.count; ++i) queue(i);
  } catch (...) {
    release();
    throw;
  }
}

void BufferRing::map_one(std::uint32_t index) {
  v4l2_buffer b{};
  b.index = index;
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  if (const int err = dev_.query_buffer(b)) throw_errno(err, "VIDIOC_QUERYBUF", path_);
  void* addr = nullptr;
  if (const int err = dev_.map(b.length, b.m.offset, addr)) throw_errno(err, "mmap", path_);
  buffers_[index] = {addr, b.length};
}

void BufferRing::release() noexcept {
  const bool had = !buffers_.empty();
  for (auto& m : buffers_)
    if (m.addr) dev_.unmap(m.addr, m.length);
  buffers_.clear();
  queued_ = 0;
  if (!had) return;
  // REQBUFS(0) frees the driver's buffers; a lost camera has nothing left to free.
  v4l2_requestbuffers req{};
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  dev_.request_buffers(req);
}

std::span<const std::uint8_t> BufferRing::data(std::uint32_t index) const {
  const Mapped& m = buffers_.at(index);
  return {static_cast<const std::uint8_t*>(m.addr), m.length};
}

void BufferRing::queue(std::uint32_t index) {
  if (index >= buffers_.size()) throw std::logic_error(path_ + ": queueing buffer " + std::to_string(index) +
                                                       " of " + std::to_string(buffers_.size()));
  v4l2_buffer b{};
  b.index = index;
  b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  b.memory = V4L2_MEMORY_MMAP;
  if (const int err = dev_.queue_buffer(b)) throw_errno(err, "VIDIOC_QBUF", path_);
  ++queued_;
}

bool BufferRing::dequeue(v4l2_buffer& buf) {
  buf = v4l2_buffer{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  const int err = dev_.dequeue_buffer(buf);
  if (err == EAGAIN || err == EINTR) return false;
  if (err) throw_errno(err, "VIDIOC_DQBUF", path_);
  if (buf.index >= buffers_.size())
    throw std::runtime_error(path_ + ": driver dequeued buffer " + std::to_string(buf.index) + " of " +
                             std::to_string(buffers_.size()));
  --queued_;
  return true;
}

// ---- Timestamps ----------------------------------------------------------------------------

// In RowTiming's model the k-th row read (k = 0 .. rows-1) starts exposing at
// t0 + k * line_delay and is read out exposure_s later. An end-of-frame stamp is taken when
// the last row, k = rows - 1, has been read: eof = t0 + (rows - 1) * line_delay + exposure,
// so t0 = eof - (rows - 1) * line_delay - exposure. (The last row's own transfer, at most one
// line delay, is inside the driver's latency and not modelled.)
std::int64_t first_row_from_end_of_frame(std::int64_t eof_ns, int rows, double line_delay_s,
                                         double exposure_s) {
  const double back_s = (std::max(rows, 1) - 1) * line_delay_s + exposure_s;
  return eof_ns - std::llround(back_s * 1e9);
}

FirstRowTime first_row_start(const v4l2_buffer& buf, int rows, double line_delay_s, double exposure_s,
                             std::int64_t dequeue_mono_ns) {
  const bool monotonic = (buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
  // The driver's stamp through rsd's one check for times from outside (dsp::Stamp).
  const bool usec_ok = buf.timestamp.tv_usec >= 0 && buf.timestamp.tv_usec < 1000000;
  const std::optional<dsp::Stamp> stamp =
      usec_ok && std::abs(static_cast<double>(buf.timestamp.tv_sec)) <= dsp::Stamp::kLimitS - 1
          ? dsp::Stamp::from_ns(std::int64_t{buf.timestamp.tv_sec} * 1000000000LL + std::int64_t{buf.timestamp.tv_usec} * 1000)
          : std::nullopt;
  if (!monotonic || !stamp)  // unknown, copied from elsewhere or absurd: the frame was complete by the dequeue
    return {first_row_from_end_of_frame(dequeue_mono_ns, rows, line_delay_s, exposure_s), false};
  const std::int64_t ts = stamp->ns();
  if ((buf.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_SOE) return {ts, true};
  return {first_row_from_end_of_frame(ts, rows, line_delay_s, exposure_s), true};  // SRC_EOF is 0
}

// ---- Sequence numbers ----------------------------------------------------------------------

std::uint64_t SequenceTracker::update(std::uint32_t seq) {
  if (!started_) {
    started_ = true;
    last_ = seq;
    unwrapped_ = seq;
    return unwrapped_;
  }
  const std::uint32_t step = seq - last_;  // modulo 2^32: a wrap-around is a small step
  last_ = seq;
  if (step == 0 || step >= 0x80000000u) {
    ++restarts_;
    return ++unwrapped_;
  }
  dropped_ += step - 1;
  unwrapped_ += step;
  return unwrapped_;
}

// ---- What an errno means -------------------------------------------------------------------

bool camera_lost(int err) {
  return err == ENODEV || err == ENXIO || err == EIO || err == ENOENT || err == EPIPE || err == ESHUTDOWN;
}

void throw_errno(int err, std::string_view call, const std::string& path) {
  const std::string why = std::strerror(err);
  if (camera_lost(err))
    throw CameraError("camera at " + path + " lost during " + std::string(call) + " (" + why +
                      "): unplugged or driver reset");
  if (err == EBUSY)
    throw CameraError("camera at " + path + " is busy (" + std::string(call) + ": " + why +
                      "): another program is streaming from it");
  throw std::runtime_error(path + ": " + std::string(call) + " failed: " + why);
}

CameraError open_error(int err, const std::string& path) {
  if (err == ENOENT || err == ENODEV || err == ENXIO)
    return CameraError("no camera at " + path +
                       " (no such device): is the camera plugged in and the uvcvideo/driver module loaded?");
  if (err == EACCES || err == EPERM)
    return CameraError("no access to camera at " + path +
                       " (permission denied): run the daemon in the 'video' group");
  if (err == EBUSY) return CameraError("camera at " + path + " is busy: another program holds it");
  return CameraError("cannot open camera at " + path + " (" + std::strerror(err) + ")");
}

}  // namespace rsd::drivers::v4l2
