// Online self-calibration in the daemon (docs/online-calibration.md): the estimator thread that
// learns the camera-IMU time offset, the line delay and the gyro bias while the camera runs.
//
// The pipeline's rectify thread offers each raw frame (FrameTap) once it has been handed on for
// publishing: its luma is copied into a free slot allocated at start, or the frame is dropped
// when every slot is busy (counted); the velocity input hands over each raw IMU measurement
// (GyroTap) into a fixed ring, dropped when full. Neither ever waits or allocates. The estimator
// thread (nice 10: it runs on what the hot path leaves) tracks features between consecutive
// frames (dsp/features), feeds them with the gyro to dsp::OnlineEstimator, fits once a second of
// frames, and for `apply` decides when the rectifier should switch to the estimate.
//
// Thread contract: offer() on the rectify thread; gyro() from the velocity input, one caller at a
// time (its writer lock); publish(), take_apply() and the rest on the service's thread; the
// estimator thread is private.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "daemon/drop_oldest_queue.hpp"
#include "daemon/lcm_publisher.hpp"
#include "daemon/pipeline.hpp"
#include "daemon/velocity_input.hpp"
#include "dsp/features/feature_tracks.hpp"
#include "dsp/online/online_estimator.hpp"
#include "formats/calibration_v1.hpp"
#include "formats/config_section.hpp"

namespace rsd::daemon {

// The estimator thread's name (the tests' allocation counter leaves it out: not the hot path).
inline constexpr char kThreadName[] = "rsd-online";

enum class OnlineMode { Off, Observe, Apply };
const char* to_string(OnlineMode m);

struct OnlineCalibrationConfig {
  OnlineMode mode = OnlineMode::Observe;
  std::string channel = "RSD_CALIBRATION";  // rsd.calibration_t, once a second
  // The last converged estimate, rsd-calibration/1, written atomically and loaded at start.
  std::string state_file;
  double max_fps = 15;       // frames handed to the estimator at most this often (pairs 1/15 s apart)
  int features = 120;        // features tracked per frame pair
  double apply_sigmas = 3;   // apply: switch again only when the estimate moved this far
  dsp::OnlineEstimatorOptions estimator;
};

// The `calibration:` section of the configuration (read or printed by the same visit).
void visit_online_calibration(formats::ConfigSection& c, OnlineCalibrationConfig& o);

// What the estimator starts from: the camera (intrinsics, nominal row timing), the IMU's mount
// and scale, and the calibration in use (or a state file's).
struct OnlineSetup {
  dsp::NominalModel nominal;
  dsp::OnlineCalibration start;
  Eigen::Vector3d gyro_scale = Eigen::Vector3d::Ones();
  formats::Calibration base;  // the calibration the state file is written from (the estimate replacing its values)
};

// calibration.state_file at start: the estimate a previous run converged to, or nothing (off, no
// file; a bad file is said in the log and ignored: it is the daemon's own state, not the user's).
// Its mount rotation is the file's T_cam_imu relative to the configured `imu_to_camera`.
std::optional<dsp::OnlineCalibration> load_online_state(const OnlineCalibrationConfig& c, const Eigen::Matrix3d& imu_to_camera);

class OnlineCalibrator final : public FrameTap, public GyroTap {
 public:
  OnlineCalibrator(const OnlineCalibrationConfig& cfg, const OnlineSetup& setup, LcmPublisher& pub);
  ~OnlineCalibrator() override;
  OnlineCalibrator(const OnlineCalibrator&) = delete;
  OnlineCalibrator& operator=(const OnlineCalibrator&) = delete;
  void start();
  void stop();

  void offer(const dsp::ImageView& raw, const drivers::FrameMeta& meta) override;  // rectify thread
  void gyro(int64_t utime_imu, const double* w_measured) override;                 // velocity input

  // Service thread. A converged estimate the rectifier should switch to (mode apply, beyond the
  // hysteresis), once; give it back with retry_apply() if it could not be applied yet.
  std::optional<dsp::OnlineCalibration> take_apply();
  void retry_apply(const dsp::OnlineCalibration& c);
  // The estimate now in use by the rectifier (mode apply), for the message.
  void set_applied(bool on) { applied_ = on; }
  // rsd.calibration_t with the latest estimate.
  void publish();
  dsp::OnlineEstimate latest() const;
  // The estimate in a few words, for the daemon's status line.
  std::string status_text() const;
  // The share of one core the estimator thread used since the previous call (service thread).
  double cpu_share();
  uint64_t frames_offered() const { return offered_.load(); }
  uint64_t frames_dropped() const { return dropped_.load(); }

 private:
  struct Slot {
    dsp::Image luma;
    double t = 0;  // first-row time, s (camera clock)
  };
  struct GyroEntry {
    double t;
    double w[3];
  };
  void run();
  void drain_gyro();
  void track(uint32_t slot);
  void after_update(const dsp::OnlineEstimate& e);
  static dsp::OnlineCalibration applicable(const dsp::OnlineEstimate& e);
  void write_state(const dsp::OnlineEstimate& e, const dsp::OnlineCalibration& v);

  OnlineCalibrationConfig cfg_;
  OnlineSetup setup_;
  LcmPublisher& pub_;
  std::unique_ptr<dsp::OnlineEstimator> est_;
  std::vector<Slot> slots_;
  FreeList free_;
  DropOldestQueue ready_;
  std::vector<GyroEntry> ring_;  // single-producer single-consumer
  alignas(64) std::atomic<uint64_t> ring_head_{0};
  alignas(64) std::atomic<uint64_t> ring_tail_{0};
  std::atomic<uint64_t> offered_{0}, dropped_{0}, gyro_dropped_{0};
  double last_offer_t_ = -1e300;     // rectify thread
  dsp::FeatureTracker tracker_;      // estimator thread: holds the frame the next one pairs with
  std::optional<double> prev_t_;     // estimator thread: that frame's first-row time, s
  double next_update_t_ = -1e300;    // estimator thread
  std::optional<dsp::OnlineCalibration> decided_;  // estimator thread: the last one handed to apply
  std::optional<dsp::OnlineCalibration> written_;  // estimator thread: the last state written
  mutable std::mutex mutex_;         // guards latest_ and pending_
  dsp::OnlineEstimate latest_;
  std::optional<dsp::OnlineCalibration> pending_;
  std::atomic<bool> applied_{false}, running_{false};
  std::atomic<double> cpu_s_{0};                  // the estimator thread's CPU time, s
  double last_cpu_s_ = 0, last_wall_s_ = 0;       // service thread: cpu_share()'s last call
  std::thread thread_;
};

}  // namespace rsd::daemon
