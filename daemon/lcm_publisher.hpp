// Publishes rsd's messages over LCM from preallocated message objects and an encode buffer,
// so that steady-state publishing makes no C++ heap allocation (LCM's C transport may copy
// the encoded bytes internally; that is outside our hot path's control).
#pragma once

#include <bot_core/image_t.hpp>
#include <lcm/lcm.h>
#include <rsd/frame_info_t.hpp>
#include <rsd/health_t.hpp>

#include <chrono>
#include <mutex>
#include <string>
#include <vector>

#include "drivers/camera_source.hpp"
#include "formats/lcm_log.hpp"

namespace rsd::daemon {

struct Channels {
  std::string image = "RSD_RECT";
  std::string raw = "RSD_RAW";
  std::string info = "RSD_FRAME_INFO";
  std::string health = "RSD_HEALTH";
};

struct ImageStamp {
  int64_t utime = 0;        // first row's capture time, Unix us (the message's utime)
  int64_t frame_utime = 0;  // the same instant, CLOCK_MONOTONIC us (metadata frame_utime)
  int64_t sequence = 0;
  double line_delay_s = 0;
  dsp::Readout readout = dsp::Readout::TopToBottom;
  double exposure_s = 0;
  bool rectified = false;
};

class LcmPublisher {
 public:
  // Throws std::runtime_error naming the URL if LCM cannot be set up.
  LcmPublisher(const std::string& url, Channels channels, const drivers::FrameFormat& fmt);
  ~LcmPublisher();
  LcmPublisher(const LcmPublisher&) = delete;
  LcmPublisher& operator=(const LcmPublisher&) = delete;

  void publish_image(bool raw, const dsp::ImageView& img, const ImageStamp& stamp);
  rsd::frame_info_t& info() { return info_; }  // fill, then publish_info()
  void publish_info();
  rsd::health_t& health() { return health_; }
  void publish_health();
  lcm_t* handle() const { return lcm_; }
  // Held around every lcm_publish through handle(); whoever else calls into the instance from
  // another thread (the velocity input's receiving, subscribing) holds it too: LCM's tcpq
  // provider is not thread-safe (drivers/lcm_receive.hpp).
  std::mutex& lcm_lock() { return publish_mutex_; }
  // rsd --record: every output (rectified image, frame info, health) is also written to this
  // log, stamped with the wall clock; raw frames are the recorder's (daemon/recording_source).
  void set_recorder(formats::LcmLogWriter* log) { record_ = log; }
  // Publishes an already encoded message (and records it, if recording).
  void publish_encoded(const std::string& channel, const void* data, size_t size);

 private:
  template <class Msg>
  void publish(const std::string& channel, const Msg& msg, std::vector<uint8_t>& buf, bool record = true);
  void set_meta(size_t index, const char* text);
  bool hub_ready();  // under publish_mutex_
  std::string url_;
  lcm_t* lcm_ = nullptr;
  Channels ch_;
  bot_core::image_t image_;
  rsd::frame_info_t info_;
  rsd::health_t health_;
  std::vector<uint8_t> buf_;
  std::vector<uint8_t> health_buf_;  // health goes out from the service's thread, the rest from the publisher's
  formats::LcmLogWriter* record_ = nullptr;
  // The publisher's, the service's and the source's threads publish through one handle, and
  // LCM's file:// provider does not serialise its writers: events interleaved and a frame was
  // lost. Held for one lcm_publish call (a memcpy, or a buffered write to a log).
  std::mutex publish_mutex_;
  // A lost tcpq hub is asked whether it answers at most once a second, each time for at most
  // this long (drivers/lcm_connect): publishing never waits longer for a silent hub.
  static constexpr int kHubProbeMs = 200;
  std::chrono::steady_clock::time_point last_probe_{};  // under publish_mutex_
  void send(const char* channel, const void* data, size_t size);
};

}  // namespace rsd::daemon
