// The `lcm` source: raw frames (bot_core.image_t with per-row timing metadata, as rsd-replay,
// lcm-logplayer or a camera node publish them) and velocity (rsd.velocity_t) received from an
// LCM URL. Messages are handled only inside capture(), in arrival order, so the velocity
// that arrived before a frame has been delivered when the frame is, and frames wait in LCM's
// queue instead of being lost while the pipeline is busy.
//
// URLs: tcpq://127.0.0.1:PORT (LCM's TCP queue; the server is lcm-java's
// lcm.lcm.TCPService), file:///abs/log?mode=r&speed=0 (a log, like a camera), memq:// (in
// process). udpm:// needs allow_multicast.
#pragma once

#include <bot_core/image_t.hpp>
#include <lcm/lcm.h>

#include <array>
#include <atomic>
#include <string>
#include <vector>

#include "formats/lcm_log.hpp"
#include "drivers/message_source.hpp"
#include "drivers/driver.hpp"
#include "drivers/tenfold_log.hpp"
#include "formats/image_t_codec.hpp"

namespace rsd::drivers {

struct LcmSourceConfig {
  std::string url = "tcpq://127.0.0.1:7700";
  std::string channel = "RSD_RAW";
  std::string velocity_channel = "RSD_VELOCITY";
  double open_timeout_s = 2;  // open() waits this long for the first frame (it fixes the format)
  double fallback_fps = 30;   // frame rate when the frames do not carry their timing
  bool allow_multicast = false;
};

class LcmSource final : public MessageSource {
 public:
  explicit LcmSource(LcmSourceConfig cfg);
  ~LcmSource() override;
  std::string name() const override { return "lcm"; }
  // Connects and waits for the first frame; CameraError (the daemon retries) when none comes.
  void open() override;
  FrameFormat format() const override { return first_.format; }
  dsp::RowTiming timing() const override { return timing_; }
  void start() override {}
  CaptureStatus capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) override;
  void stop() override {}
  std::optional<dsp::CameraModel> recorded_camera() const override { return first_.camera; }
  uint64_t skipped(formats::LogSkip r) const { return skips_[static_cast<size_t>(r)].load(std::memory_order_relaxed); }
  // Messages on the frame, velocity and pose channels refused, all reasons.
  uint64_t refused() const override;

 private:
  static void on_image(const lcm_recv_buf_t* rbuf, const char* channel, void* user);
  static void on_velocity(const lcm_recv_buf_t* rbuf, const char* channel, void* user);
  static void on_pose(const lcm_recv_buf_t* rbuf, const char* channel, void* user);
  void skip(formats::LogSkip r, const std::string& detail);
  void close_lcm();
  LcmSourceConfig cfg_;
  lcm_t* lcm_ = nullptr;
  std::array<lcm_subscription_t*, 3> subs_{};  // frame, velocity, pose (null when not subscribed)
  formats::RecordedFrame first_, frame_;
  dsp::RowTiming timing_;
  bot_core::image_t img_;
  std::string why_;
  bool opening_ = false, got_frame_ = false, pending_ = false;
  dsp::Image pending_image_;  // the frame open() waited for, delivered by the first capture()
  FrameMeta pending_meta_;
  std::vector<rsd::velocity_t> early_velocity_;  // received while open() waited: delivered before that frame
  std::vector<bot_core::pose_t> early_pose_;
  const dsp::ImageView* target_ = nullptr;
  FrameMeta* target_meta_ = nullptr;
  std::array<std::atomic<uint64_t>, formats::kLogSkipKinds> skips_{};  // written by the capture thread
  std::array<TenfoldLog, formats::kLogSkipKinds> skip_log_{};
  dsp::TimeLine line_ = frame_time_line();  // the frames' first rows (a new connection starts it again)
};

// The driver's entry (drivers/driver_registry.cpp) and its config section (source.lcm).
Driver lcm_driver();
void visit_config(formats::ConfigSection& c, LcmSourceConfig& s);

}  // namespace rsd::drivers
