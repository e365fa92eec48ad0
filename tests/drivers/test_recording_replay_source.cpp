// The images-recording source (rsd --replay DIR): pictures out as frames with frames.csv's
// stamps and numbers, the recording's row timing (or a calibration's), and the motion handed
// to the velocity input ahead of each frame: every sample its readout needs, none far beyond.
// A trajectory becomes body rates: checked against a screw motion with known rates.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>

#include "drivers/recording_replay_source.hpp"
#include "formats/image_file.hpp"
#include "formats/video_file.hpp"
#include "tests/support/temp_dir.hpp"

using namespace rsd;
namespace fs = std::filesystem;

namespace {

// The test's directories, inside one of this process's that goes when it ends.
const rsd::test::TempDir& g_tmp = rsd::test::register_temp_dir("rsd-test-recsrc-");

fs::path temp_dir(const std::string& name) {
  const fs::path p = g_tmp.path(name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

Eigen::Quaterniond exp_q(const Eigen::Vector3d& r) {
  return r.norm() > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(r.norm(), r.normalized())) : Eigen::Quaterniond::Identity();
}

// An images recording's header: 32x24 pictures at 20 Hz, a gyro, line delay 1 ms.
formats::ImagesRecording gyro_recording_32x24() {
  formats::ImagesRecording r;
  r.rec.kind = dsp::ObservationKind::Matches;
  r.rec.motion = dsp::MotionKind::Gyro;
  r.rec.nominal.cam.width = 32, r.rec.nominal.cam.height = 24;
  r.rec.nominal.cam.fx = r.rec.nominal.cam.fy = 30, r.rec.nominal.cam.cx = 15.5, r.rec.nominal.cam.cy = 11.5;
  r.rec.nominal.frame_rate_hz = 20;
  r.rec.nominal.time.line_delay_s = 1e-3;
  return r;
}

// Four 32x24 frames at 20 Hz starting at t = 100 s, numbered 7..10, in a video; a 1 kHz gyro
// from 99.9 s; line delay 1 ms (a 24 ms readout); nominal offset 5 ms.
fs::path gyro_video_recording() {
  const fs::path dir = temp_dir("video");
  formats::ImagesRecording r = gyro_recording_32x24();
  r.rec.nominal.time.time_offset_s = 0.005;
  r.video = (dir / "capture.avi").string();
  formats::VideoWriter w(r.video, 32, 24, 20);
  for (int k = 0; k < 12; ++k) {
    dsp::Image img(32, 24, dsp::PixelFormat::Mono8);
    img.data.assign(img.data.size(), static_cast<uint8_t>(10 * k));
    w.write(img.view());
  }
  for (int k = 0; k < 4; ++k) {
    r.rec.frames.push_back({7 + k, 100.0 + 0.05 * k});
    r.files.push_back(std::to_string(7 + k));  // the video's frames 7..10
  }
  for (int k = 0; k < 400; ++k) r.rec.gyro.push_back({99.9 + 1e-3 * k, {0.1, 0.2, 0.3 + 1e-3 * k}});
  formats::write_images_recording(dir.string(), r);
  return dir;
}

}  // namespace

TEST(BodyRates, ScrewMotionGivesItsBodyRatesAndVelocity) {
  const Eigen::Vector3d w(0.3, -0.2, 0.5), v_world(1.0, 0.5, -0.25);
  const Eigen::Quaterniond q0 = exp_q({0.1, 0.2, 0.3});
  std::vector<dsp::PoseSample> poses;
  for (int k = 0; k <= 20; ++k) {
    const double t = 0.01 * k;
    poses.push_back({t, v_world * t, q0 * exp_q(w * t)});  // R(t) = R0 Exp(w t): constant body rate
  }
  poses.push_back({0.2, v_world * 0.2, q0 * exp_q(w * 0.2)});  // a repeated stamp is skipped
  const std::vector<drivers::VelocitySample> s = drivers::body_rates(poses);
  ASSERT_EQ(s.size(), 20u);
  for (const drivers::VelocitySample& x : s) {
    EXPECT_TRUE(x.imu_frame);
    EXPECT_TRUE(x.has_linear);
    const double t = x.t_ns * 1e-9;
    const Eigen::Vector3d v_body = (q0 * exp_q(w * t)).conjugate() * v_world;
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(x.w[i], w[i], 1e-9);
      EXPECT_NEAR(x.v[i], v_body[i], 1e-4);  // the midpoint rotation of a 10 ms step
    }
  }
}

TEST(RecordingReplaySource, PlaysPicturesWithStampsNumbersAndMotionAhead) {
  const fs::path dir = gyro_video_recording();
  drivers::RecordingReplayConfig cfg;
  cfg.dir = dir.string();
  cfg.speed = 0;
  drivers::RecordingReplaySource src(cfg);
  std::vector<drivers::VelocitySample> motion;
  src.set_velocity_sink([&](const drivers::VelocitySample& s) { motion.push_back(s); });
  src.open();
  EXPECT_EQ(src.format().width, 32);
  EXPECT_EQ(src.format().format, dsp::PixelFormat::Rgb8);  // decoded video
  EXPECT_DOUBLE_EQ(src.timing().line_delay_s, 1e-3);
  EXPECT_DOUBLE_EQ(src.timing().frame_rate_hz, 20);
  EXPECT_TRUE(src.fast());
  src.start();
  dsp::Image img(32, 24, dsp::PixelFormat::Rgb8);
  drivers::FrameMeta meta;
  for (int k = 0; k < 4; ++k) {
    ASSERT_EQ(src.capture(img.view(), meta, std::chrono::milliseconds(100)), drivers::CaptureStatus::Frame);
    EXPECT_EQ(meta.sequence, static_cast<uint64_t>(7 + k));
    EXPECT_EQ(meta.first_row_ns, std::llround((100.0 + 0.05 * k) * 1e9));
    EXPECT_NEAR(img.data[0], 10 * (7 + k), 4);  // the video's frame 7 + k (Motion-JPEG: a few levels)
    // Motion up to the last row (24 ms) + the nominal offset (5 ms) + the lead (50 ms), no more.
    const double until = 100.0 + 0.05 * k + 0.024 + 0.005 + 0.05;
    ASSERT_FALSE(motion.empty());
    EXPECT_TRUE(motion.back().imu_frame);
    EXPECT_LE(motion.back().t_ns * 1e-9, until + 1e-9);
    EXPECT_GT(motion.back().t_ns * 1e-9, until - 1.001e-3);
  }
  EXPECT_EQ(src.capture(img.view(), meta, std::chrono::milliseconds(100)), drivers::CaptureStatus::EndOfStream);
  EXPECT_EQ(motion.size(), 400u);  // the rest at the end: nothing lost
  EXPECT_EQ(src.frames(), 4u);
  EXPECT_DOUBLE_EQ(src.progress(), 1.0);
}

TEST(RecordingReplaySource, CalibratedRowTimingReplacesTheNominal) {
  const fs::path dir = gyro_video_recording();
  const drivers::Driver d = drivers::recording_driver();
  std::any cfg = d.defaults();
  std::any_cast<drivers::RecordingReplayConfig&>(cfg).dir = dir.string();
  d.use_row_timing(cfg, 1.1e-3, dsp::Readout::BottomToTop, true);
  auto src = d.make(cfg);
  src->open();
  EXPECT_DOUBLE_EQ(src->timing().line_delay_s, 1.1e-3);
  EXPECT_EQ(src->timing().readout, dsp::Readout::BottomToTop);
}

// A calibration that puts the IMU clock 0.3 s ahead (a phone's gyro log): each frame then needs
// motion stamped 0.3 s later, and gets it before it is captured.
TEST(RecordingReplaySource, ACalibratedClockOffsetMovesTheMotionAhead) {
  const fs::path dir = gyro_video_recording();
  const drivers::Driver d = drivers::recording_driver();
  std::any cfg = d.defaults();
  std::any_cast<drivers::RecordingReplayConfig&>(cfg).dir = dir.string();
  std::any_cast<drivers::RecordingReplayConfig&>(cfg).speed = 0;
  d.use_clock_offset(cfg, 0.1);
  auto src = d.make(cfg);
  std::vector<drivers::VelocitySample> motion;
  src->set_velocity_sink([&](const drivers::VelocitySample& s) { motion.push_back(s); });
  src->open();
  src->start();
  dsp::Image img(32, 24, dsp::PixelFormat::Rgb8);
  drivers::FrameMeta meta;
  ASSERT_EQ(src->capture(img.view(), meta, std::chrono::milliseconds(100)), drivers::CaptureStatus::Frame);
  ASSERT_FALSE(motion.empty());
  EXPECT_NEAR(motion.back().t_ns * 1e-9, 100.0 + 0.024 + 0.1 + 0.05, 1.001e-3);
}

TEST(RecordingReplaySource, RecordingsOfObservationsAreRefusedByName) {
  const fs::path dir = temp_dir("obs");
  dsp::Recording r;
  r.kind = dsp::ObservationKind::Matches;
  r.motion = dsp::MotionKind::Gyro;
  r.frames = {{0, 0.0}};
  r.gyro = {{0, {0, 0, 0}}, {1, {0, 0, 0}}};
  formats::write_recording(dir.string(), r);
  drivers::RecordingReplayConfig cfg;
  cfg.dir = dir.string();
  drivers::RecordingReplaySource src(cfg);
  try {
    src.open();
    FAIL() << "a matches recording played as pictures";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("observations.kind is matches, not images"), std::string::npos) << e.what();
  }
}

// A bad later picture (truncated, missing, another size) is refused, counted and named in the
// log; the pictures after it play as if it were not there (issue 38: it used to end the capture
// thread with an uncaught exception, and rsd with SIGABRT).
TEST(RecordingReplaySource, ABadLaterPictureIsRefusedAndThePlayGoesOn) {
  const fs::path dir = temp_dir("bad-picture");
  formats::ImagesRecording r = gyro_recording_32x24();
  for (int k = 0; k < 6; ++k) {
    char name[16];
    std::snprintf(name, sizeof name, "f%d.png", k);
    const fs::path file = dir / name;
    dsp::Image img(k == 3 ? 16 : 32, 24, dsp::PixelFormat::Mono8);  // picture 3: another size
    img.data.assign(img.data.size(), static_cast<uint8_t>(10 * k));
    formats::write_png(file.string(), img.view());
    r.rec.frames.push_back({k, 0.05 * k});
    r.files.push_back(file.string());
  }
  for (int k = 0; k < 400; ++k) r.rec.gyro.push_back({-0.1 + 1e-3 * k, {0.1, 0.2, 0.3}});
  formats::write_images_recording(dir.string(), r);
  fs::resize_file(dir / "f1.png", 40);  // truncated
  fs::remove(dir / "f4.png");           // missing
  drivers::RecordingReplayConfig cfg;
  cfg.dir = dir.string();
  cfg.speed = 0;
  drivers::RecordingReplaySource src(cfg);
  src.open();
  src.start();
  dsp::Image img(32, 24, dsp::PixelFormat::Mono8);
  drivers::FrameMeta meta;
  std::vector<uint64_t> played;
  for (int calls = 0; calls < 20; ++calls) {
    const drivers::CaptureStatus st = src.capture(img.view(), meta, std::chrono::milliseconds(100));
    if (st == drivers::CaptureStatus::EndOfStream) break;
    if (st != drivers::CaptureStatus::Frame) continue;
    played.push_back(meta.sequence);
    EXPECT_EQ(img.data[0], 10 * meta.sequence);  // each played frame is its own picture
  }
  EXPECT_EQ(played, (std::vector<uint64_t>{0, 2, 5}));
  EXPECT_EQ(src.refused(), 3u);
  EXPECT_EQ(src.frames(), 3u);
  EXPECT_EQ(src.capture(img.view(), meta, std::chrono::milliseconds(100)), drivers::CaptureStatus::EndOfStream);
}
