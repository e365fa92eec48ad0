// The online self-calibration end to end (issues 18 and 36, docs/online-calibration.md). The
// simulated camera hides its IMU clock (15 ms ahead of the camera's), its rolling shutter (60 us
// a row) and a gyro bias of 0.01 rad/s on each axis, and is shaken by hand. Recorded as an
// images recording whose recording.yaml gives no line delay (a user's first configuration:
// nobody measured it) and replayed in real time through the daemon (rsd --replay DIR) with
// calibration.online: apply, the estimator learns them while the frames go by, the line delay
// from 0: the state file it writes holds them within the tolerances, says the rows are
// read one after another, and agrees with the offline diagnosis of the same pictures (what
// rsd-diagnose finds); rectifying with it brings the error against the simulator's
// global-shutter truth within 0.3 px RMS.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>

#include "daemon/config.hpp"
#include "daemon/service.hpp"
#include "drivers/recording_replay_source.hpp"
#include "formats/calibration_v1.hpp"
#include "tests/daemon/closed_loop_support.hpp"

using namespace rsd;
using namespace rsd::test;
namespace fs = std::filesystem;

namespace {

constexpr double kNominalLineDelay = 5e-5, kTrueOffset = 0.015, kTrueBias = 0.01;

// A hand-held camera: a wobble of the rate about changing axes on a slow turn, no translation.
SimRig hand_held() {
  SimRig r;
  drivers::SimSourceConfig& t = r.truth;
  t.camera = dsp::CameraModel::from_hfov(kW, kH, M_PI / 3);
  t.line_delay_s = 1.2 * kNominalLineDelay;
  t.angular_rate = {0.1, -0.1, 0.05};
  t.wobble_rad_s = 1.0, t.wobble_hz = 0.8;
  t.wobble_axes = {1.0, 0.8, 0.6}, t.wobble_axes_hz = {1.0, 1.37, 0.71};
  t.velocity = Eigen::Vector3d::Zero();
  t.exposure_s = 0;
  t.noise_grey = 0.5;
  t.supersample = 2;
  t.realtime = false;
  t.velocity_rate_hz = 400;
  t.imu_time_offset_s = kTrueOffset;
  t.gyro_bias = Eigen::Vector3d::Constant(kTrueBias);
  r.nominal.cam = t.camera;
  r.nominal.frame_rate_hz = 30;
  r.nominal.time.line_delay_s = 0;  // not measured yet
  return r;
}

// The daemon replays the recording in real time (the estimator keeps pace, as with a live
// camera) with calibration.online: apply.
daemon::RunSummary replay_learning(const fs::path& dir, const SimRig& r) {
  daemon::Config cfg = replay_of(dir);
  cfg.source.settings_of<drivers::RecordingReplayConfig>("recording").speed = 1;
  daemon::apply_calibration(cfg, formats::calibration_of(r.nominal, "nominal"));
  cfg.online.mode = daemon::OnlineMode::Apply;
  cfg.online.state_file = (dir / "state.yaml").string();
  daemon::StopFlags flags;
  daemon::RunLimits limits;
  limits.status_line = false;
  daemon::RunSummary summary;
  daemon::run_service(cfg, flags, limits, {}, &summary);
  return summary;
}

void expect_within_goal(const char* what, const formats::Calibration& c) {
  EXPECT_NEAR(c.timeshift_cam_imu_s, kTrueOffset, 0.5e-3) << what;
  EXPECT_NEAR(c.line_delay_s / (1.2 * kNominalLineDelay), 1.0, 0.03) << what;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(c.gyro_bias_rad_s[i], kTrueBias, 0.002) << what << ", bias axis " << i;
}

}  // namespace

TEST(OnlineCalibration, LearnsWhileAnImagesRecordingReplays) {
  const SimRig r = hand_held();
  const fs::path dir = fs::temp_directory_path() / ("rsd-online-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const int64_t t0 = record(r, 120, dir);  // 4 s: it converges in about two
  const daemon::RunSummary run = replay_learning(dir, r);
  ASSERT_TRUE(run.online.has_value());
  EXPECT_TRUE(run.online->converged) << run.online->reason;
  ASSERT_TRUE(run.online_applied.has_value()) << "the rectifier never switched to the estimate";
  ASSERT_TRUE(fs::exists(dir / "state.yaml"));
  const formats::Calibration online = formats::read_calibration((dir / "state.yaml").string());
  std::printf("[online] time offset %.3f ms, line delay %.3f us, bias (%.4f %.4f %.4f) after %d updates\n",
              online.timeshift_cam_imu_s * 1e3, online.line_delay_s * 1e6, online.gyro_bias_rad_s.x(),
              online.gyro_bias_rad_s.y(), online.gyro_bias_rad_s.z(), run.online->updates);
  expect_within_goal("online", online);
  // The file says how it knows: the rows shown rolling, the line delay learned from nothing.
  EXPECT_NE(online.source.find("unknown shutter, rows rolling"), std::string::npos) << online.source;
  EXPECT_NE(online.source.find("line delay learned"), std::string::npos) << online.source;

  // The offline diagnosis of the same pictures says the same, within the same tolerances.
  const formats::Calibration offline = learn(dir, "online-offline");
  EXPECT_NEAR(online.timeshift_cam_imu_s, offline.timeshift_cam_imu_s, 0.5e-3);
  EXPECT_NEAR(online.line_delay_s / offline.line_delay_s, 1.0, 0.03);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(online.gyro_bias_rad_s[i], offline.gyro_bias_rad_s[i], 0.002) << "axis " << i;

  // Rectified with what the daemon learned: within 0.3 px of the truth (the nominal: far off).
  SimTruth truth(r, t0);
  const Measured nominal = rectified_rms(replay_of(dir), formats::calibration_of(r.nominal, "nominal"), std::ref(truth));
  const Measured learned = rectified_rms(replay_of(dir), online, std::ref(truth));
  std::printf("[online] rectified RMS against the global-shutter truth: nominal %.3f px, learned online %.3f px\n", nominal.rms,
              learned.rms);
  EXPECT_GT(nominal.rms, 0.5);
  EXPECT_LT(learned.rms, 0.3);
  fs::remove_all(dir);
}
