// calibration.state_file read at start (daemon/online_calibration): what a previous run converged
// to, written by the one calibration writer; nothing when off or absent; a damaged file is said
// and ignored, never a crash or a refusal to start.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "daemon/online_calibration.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "formats/calibration_v1.hpp"

using namespace rsd;
namespace fs = std::filesystem;

namespace {

struct StateFile {
  fs::path path = fs::temp_directory_path() / ("rsd-online-state-" + std::to_string(::getpid()) + ".yaml");
  ~StateFile() { fs::remove(path); }
};

daemon::OnlineCalibrationConfig config(const StateFile& f, daemon::OnlineMode mode = daemon::OnlineMode::Apply) {
  daemon::OnlineCalibrationConfig c;
  c.mode = mode;
  c.state_file = f.path.string();
  return c;
}

}  // namespace

TEST(OnlineState, ReadsBackWhatTheWriterWrote) {
  StateFile f;
  formats::Calibration cal = formats::calibration_of(dsp::NominalModel{}, "test");
  cal.timeshift_cam_imu_s = 0.0151, cal.line_delay_s = 6.01e-5, cal.gyro_bias_rad_s = {0.01, -0.02, 0.03};
  const Eigen::Matrix3d configured = dsp::exp_so3({0, 0.5, 0});           // the configuration's mount
  cal.imu_to_camera = dsp::exp_so3({0.01, -0.005, 0.002}) * configured;   // and the one learned
  formats::write_calibration(f.path.string(), cal);
  EXPECT_FALSE(fs::exists(f.path.string() + ".tmp"));  // written beside it, then renamed
  const auto s = daemon::load_online_state(config(f), configured);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->time_offset_s, 0.0151);
  EXPECT_EQ(s->line_delay_s, 6.01e-5);
  EXPECT_EQ(s->gyro_bias, Eigen::Vector3d(0.01, -0.02, 0.03));
  EXPECT_LT((s->mount_rotation - Eigen::Vector3d(0.01, -0.005, 0.002)).norm(), 1e-9);
  EXPECT_FALSE(daemon::load_online_state(config(f, daemon::OnlineMode::Off), Eigen::Matrix3d::Identity()).has_value());
}

TEST(OnlineState, MissingOrDamagedFilesStartFromTheConfiguration) {
  StateFile f;
  EXPECT_FALSE(daemon::load_online_state(config(f), Eigen::Matrix3d::Identity()).has_value());  // absent: a first run
  std::ofstream(f.path) << "cam0:\n  camera_model: pinhole\n  intrinsics: [1, 2\n";  // cut short
  EXPECT_FALSE(daemon::load_online_state(config(f), Eigen::Matrix3d::Identity()).has_value());
  std::ofstream(f.path) << "cam0:\n  timeshift_cam_imu: 0.01\n";  // Kalibr's keys only: no line delay
  EXPECT_FALSE(daemon::load_online_state(config(f), Eigen::Matrix3d::Identity()).has_value());
}
