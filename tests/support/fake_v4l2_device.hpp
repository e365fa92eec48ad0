// A fake V4l2Device for the V4L2 source's tests: it offers formats, grants buffers, hands out
// frames with chosen sequence numbers, flags and stamps, and fails on request, recording
// every call the source makes.
#pragma once

#include <cerrno>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "drivers/v4l2_logic.hpp"
#include "drivers/v4l2_source.hpp"

namespace rsd::drivers::test {

using v4l2::Layout;

// ---- A fake device -------------------------------------------------------------------------

struct FakeFrame {
  std::vector<std::uint8_t> bytes;
  std::uint32_t flags = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE;
  timeval stamp{};
  std::uint32_t sequence = 0;
  long bytesused = -1;  // -1: bytes.size()
};

// What the fake driver offers and what the test can observe, shared with the device object
// (which the source owns).
struct FakeState {
  std::uint32_t caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  int querycap_error = 0;
  std::vector<std::uint32_t> formats{V4L2_PIX_FMT_GREY};
  std::vector<v4l2_frmsizeenum> sizes;      // empty: ENUM_FRAMESIZES unsupported
  std::uint32_t row_padding = 0;            // bytesperline = packed row + this
  bool can_set_rate = true;
  std::vector<double> rates{30.0};          // the driver snaps to the nearest
  int exposure_100us = 0;                   // 0: no exposure control
  unsigned grant = 0;                       // 0: grant what is asked
  std::map<std::string, int> fail;          // call name -> errno
  std::deque<FakeFrame> frames;
  // Observed.
  std::vector<std::vector<std::uint8_t>> memory;
  std::deque<std::uint32_t> queued;
  bool streaming = false;
  int maps = 0, unmaps = 0, reqbufs_zero = 0;
  v4l2_format format{};
  double rate = 30.0;
};

v4l2_frmsizeenum discrete(std::uint32_t w, std::uint32_t h) {
  v4l2_frmsizeenum s{};
  s.type = V4L2_FRMSIZE_TYPE_DISCRETE;
  s.discrete = {w, h};
  return s;
}

class FakeDevice final : public V4l2Device {
 public:
  explicit FakeDevice(std::shared_ptr<FakeState> s) : s_(std::move(s)) {}
  int query_cap(v4l2_capability& c) override {
    std::strcpy(reinterpret_cast<char*>(c.card), "Fake Cam");
    std::strcpy(reinterpret_cast<char*>(c.driver), "fake");
    c.capabilities = s_->caps;
    return s_->querycap_error;
  }
  int enum_format(v4l2_fmtdesc& d) override {
    if (d.index >= s_->formats.size()) return EINVAL;
    d.pixelformat = s_->formats[d.index];
    return 0;
  }
  int enum_frame_size(v4l2_frmsizeenum& e) override {
    if (s_->sizes.empty()) return ENOTTY;
    if (e.index >= s_->sizes.size()) return EINVAL;
    const std::uint32_t i = e.index, f = e.pixel_format;
    e = s_->sizes[i];
    e.index = i;
    e.pixel_format = f;
    return 0;
  }
  int set_format(v4l2_format& f) override {
    if (int e = failure("S_FMT")) return e;
    auto& p = f.fmt.pix;
    const auto* info = v4l2::pixel_info(p.pixelformat);
    const dsp::PixelFormat pf = info ? info->layout.format : dsp::PixelFormat::Mono8;
    p.bytesperline = static_cast<std::uint32_t>(dsp::row_bytes(pf, static_cast<int>(p.width))) + s_->row_padding;
    p.sizeimage = p.bytesperline * static_cast<std::uint32_t>(dsp::buffer_rows(pf, static_cast<int>(p.height)));
    p.field = V4L2_FIELD_NONE;
    s_->format = f;
    return 0;
  }
  int get_parm(v4l2_streamparm& p) override {
    p.parm.capture.capability = s_->can_set_rate ? V4L2_CAP_TIMEPERFRAME : 0;
    p.parm.capture.timeperframe = {1000, static_cast<std::uint32_t>(s_->rate * 1000)};
    return 0;
  }
  int set_parm(v4l2_streamparm& p) override {
    const double want = double(p.parm.capture.timeperframe.denominator) / p.parm.capture.timeperframe.numerator;
    double best = s_->rates.front();
    for (double r : s_->rates)
      if (std::abs(r - want) < std::abs(best - want)) best = r;
    s_->rate = best;
    return get_parm(p);
  }
  int get_control(v4l2_control& c) override {
    if (c.id != V4L2_CID_EXPOSURE_ABSOLUTE || s_->exposure_100us == 0) return EINVAL;
    c.value = s_->exposure_100us;
    return 0;
  }
  int request_buffers(v4l2_requestbuffers& r) override {
    if (r.count == 0) {
      ++s_->reqbufs_zero;
      s_->memory.clear();
      return 0;
    }
    if (s_->grant) r.count = s_->grant;
    s_->memory.assign(r.count, std::vector<std::uint8_t>(s_->format.fmt.pix.sizeimage));
    return 0;
  }
  int query_buffer(v4l2_buffer& b) override {
    b.length = static_cast<std::uint32_t>(s_->memory.at(b.index).size());
    b.m.offset = b.index * 4096;
    return 0;
  }
  int queue_buffer(v4l2_buffer& b) override {
    if (int e = failure("QBUF")) return e;
    s_->queued.push_back(b.index);
    return 0;
  }
  int dequeue_buffer(v4l2_buffer& b) override;
  int stream_on() override {
    if (int e = failure("STREAMON")) return e;
    s_->streaming = true;
    return 0;
  }
  int stream_off() override {
    s_->streaming = false;
    s_->queued.clear();
    return 0;
  }
  int wait_readable(int, bool& ready) override {
    if (int e = failure("poll")) return e;
    ready = s_->streaming && !s_->queued.empty() && (!s_->frames.empty() || s_->fail.count("DQBUF"));
    return 0;
  }
  int map(std::size_t, std::uint32_t offset, void*& addr) override {
    addr = s_->memory.at(offset / 4096).data();
    ++s_->maps;
    return 0;
  }
  void unmap(void*, std::size_t) override { ++s_->unmaps; }

 private:
  int failure(const std::string& call) const {
    const auto it = s_->fail.find(call);
    return it == s_->fail.end() ? 0 : it->second;
  }
  std::shared_ptr<FakeState> s_;
};

int FakeDevice::dequeue_buffer(v4l2_buffer& b) {
  if (int e = failure("DQBUF")) return e;
  if (s_->frames.empty() || s_->queued.empty()) return EAGAIN;
  const FakeFrame f = s_->frames.front();
  s_->frames.pop_front();
  b.index = s_->queued.front();
  s_->queued.pop_front();
  auto& mem = s_->memory[b.index];
  std::copy(f.bytes.begin(), f.bytes.begin() + std::min(f.bytes.size(), mem.size()), mem.begin());
  b.bytesused = static_cast<std::uint32_t>(f.bytesused < 0 ? f.bytes.size() : f.bytesused);
  b.flags = f.flags;
  b.timestamp = f.stamp;
  b.sequence = f.sequence;
  return 0;
}

V4l2Opener fake_opener(const std::shared_ptr<FakeState>& s) {
  return [s](const std::string&) { return std::make_unique<FakeDevice>(s); };
}

// A width x height YUYV frame, rows `stride` bytes apart, luma = 10 * y + x, chroma 0x80,
// padding bytes 0xEE.
std::vector<std::uint8_t> yuyv_frame(int width, int height, std::size_t stride) {
  std::vector<std::uint8_t> b(stride * height, 0xEE);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      b[y * stride + 2 * x] = static_cast<std::uint8_t>(10 * y + x);
      b[y * stride + 2 * x + 1] = 0x80;
    }
  return b;
}

}  // namespace rsd::drivers::test
