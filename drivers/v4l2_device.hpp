// A thin seam over the V4L2 ioctls and mmap calls the V4L2 source makes, so that everything
// above it (format negotiation, buffer bookkeeping, timestamps, error mapping) runs against a
// fake device in unit tests. One method per ioctl, with the kernel's own structs.
//
// Every call returns 0 or an errno value and never throws: the caller decides what an error
// means (a lost camera, a driver that lacks a feature, a bug of ours).
#pragma once

#include <linux/videodev2.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace rsd::drivers {

class V4l2Device {
 public:
  virtual ~V4l2Device() = default;
  virtual int query_cap(v4l2_capability& cap) = 0;             // VIDIOC_QUERYCAP
  virtual int enum_format(v4l2_fmtdesc& desc) = 0;             // VIDIOC_ENUM_FMT
  virtual int enum_frame_size(v4l2_frmsizeenum& size) = 0;     // VIDIOC_ENUM_FRAMESIZES
  virtual int set_format(v4l2_format& fmt) = 0;                // VIDIOC_S_FMT
  virtual int get_parm(v4l2_streamparm& parm) = 0;             // VIDIOC_G_PARM
  virtual int set_parm(v4l2_streamparm& parm) = 0;             // VIDIOC_S_PARM
  virtual int get_control(v4l2_control& ctrl) = 0;             // VIDIOC_G_CTRL
  virtual int request_buffers(v4l2_requestbuffers& req) = 0;   // VIDIOC_REQBUFS
  virtual int query_buffer(v4l2_buffer& buf) = 0;              // VIDIOC_QUERYBUF
  virtual int queue_buffer(v4l2_buffer& buf) = 0;              // VIDIOC_QBUF
  virtual int dequeue_buffer(v4l2_buffer& buf) = 0;            // VIDIOC_DQBUF (non-blocking)
  virtual int stream_on() = 0;                                 // VIDIOC_STREAMON, video capture
  virtual int stream_off() = 0;                                // VIDIOC_STREAMOFF, video capture
  // poll() for a filled buffer: 0 with `ready` telling whether one is there, or an errno value.
  virtual int wait_readable(int timeout_ms, bool& ready) = 0;
  // mmap of the buffer the driver placed at `offset`: 0 with `addr` set, or an errno value.
  virtual int map(std::size_t length, std::uint32_t offset, void*& addr) = 0;
  virtual void unmap(void* addr, std::size_t length) = 0;
};

// Opens a V4L2 node; throws CameraError when there is no usable camera there.
using V4l2Opener = std::function<std::unique_ptr<V4l2Device>(const std::string& path)>;

// The real device: open(2) + ioctl(2) + mmap(2) on a /dev/video node (in v4l2_source.cpp,
// the only file that touches the kernel).
std::unique_ptr<V4l2Device> open_v4l2_device(const std::string& path);

}  // namespace rsd::drivers
