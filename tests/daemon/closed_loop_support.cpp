#include "tests/daemon/closed_loop_support.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm.h>

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <cmath>
#include <cstdio>

#include "daemon/frame_rectifier.hpp"
#include "daemon/velocity_input.hpp"
#include "drivers/message_source.hpp"
#include "drivers/recording_replay_source.hpp"
#include "dsp/diagnosis/diagnosis.hpp"
#include "formats/image_file.hpp"
#include "formats/recording_v1.hpp"
#include "tools/common/picture_observations.hpp"
#include "tools/report/diagnosis_calibration.hpp"

namespace rsd::test {

namespace fs = std::filesystem;

int64_t record(const SimRig& r, int frames, const fs::path& dir) {
  constexpr int kMargin = 10;
  drivers::SimSource sim(r.truth);
  formats::ImagesRecording rec;
  rec.rec.kind = dsp::ObservationKind::Matches;
  rec.rec.motion = dsp::MotionKind::Gyro;
  rec.rec.nominal = r.nominal;
  sim.set_velocity_sink([&](const drivers::VelocitySample& s) {
    rec.rec.gyro.push_back({s.t_ns * 1e-9, {s.w[0], s.w[1], s.w[2]}});
  });
  sim.open();
  sim.start();
  fs::create_directories(dir / "frames");
  dsp::Image img(kW, kH, dsp::PixelFormat::Mono8);
  int64_t t0 = 0;
  for (int k = 0; k < frames + 2 * kMargin; ++k) {
    drivers::FrameMeta meta;
    EXPECT_EQ(sim.capture(img.view(), meta, std::chrono::milliseconds(1000)), drivers::CaptureStatus::Frame);
    if (k == 0) t0 = meta.first_row_ns;
    if (k < kMargin || k >= frames + kMargin) continue;
    const std::string file = (dir / "frames" / (std::to_string(k) + ".png")).string();
    formats::write_png(file, img.view());
    rec.rec.frames.push_back({k, meta.first_row_ns * 1e-9});
    rec.files.push_back(file);
  }
  formats::write_images_recording(dir.string(), rec);
  return t0;
}

namespace {

// Displacements of features found in `ref` and tracked into `img`, well inside the image; a
// track that does not come back to its start when tracked back (a tracking failure, not a
// displacement) is left out.
void add_shifts(const cv::Mat& ref, const cv::Mat& img, double& sum, int& n) {
  std::vector<cv::Point2f> p0, p1, back;
  cv::goodFeaturesToTrack(ref, p0, 200, 0.01, 6, cv::noArray(), 7);
  if (p0.empty()) return;
  std::vector<uchar> ok, ok_back;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(ref, img, p0, p1, ok, err, cv::Size(21, 21), 3);
  cv::calcOpticalFlowPyrLK(img, ref, p1, back, ok_back, err, cv::Size(21, 21), 3);
  for (size_t i = 0; i < p0.size(); ++i) {
    if (!ok[i] || !ok_back[i] || std::hypot(back[i].x - p0[i].x, back[i].y - p0[i].y) > 0.1) continue;
    if (p0[i].x < 30 || p0[i].y < 30 || p0[i].x > ref.cols - 30 || p0[i].y > ref.rows - 30) continue;
    const double dx = p1[i].x - p0[i].x, dy = p1[i].y - p0[i].y;
    sum += dx * dx + dy * dy, ++n;
  }
}

}  // namespace

Measured rectified_rms(daemon::Config cfg, const formats::Calibration& cal, const TruthRender& render_truth) {
  daemon::apply_calibration(cfg, cal);
  auto src = daemon::make_source(cfg.source);
  lcm_t* lcm = lcm_create("memq://");
  daemon::VelocityBuffer buf;
  double sum = 0;
  int n = 0;
  Measured out;
  {
    daemon::VelocityInput in(lcm, "RSD_VELOCITY_TEST", buf, cfg.velocity_input);
    auto* m = dynamic_cast<drivers::MessageSource*>(src.get());  // an LCM log: velocity and pose messages
    if (m && !cfg.velocity_input.pose_channel.empty())
      m->set_pose_message_sink(cfg.velocity_input.pose_channel, [&](const bot_core::pose_t& p) { in.deliver(p); });
    if (m) m->set_velocity_message_sink([&](const rsd::velocity_t& msg) { in.deliver(msg); });
    else src->set_velocity_sink([&](const drivers::VelocitySample& s) { in.deliver(s); });
    src->open();
    daemon::FrameRectifier rect(cfg.rectify, daemon::camera_model(cfg.source, src->format()), src->timing(), src->format());
    dsp::Image raw(kW, kH, dsp::PixelFormat::Mono8), rectified = raw, truth = raw;
    src->start();
    drivers::FrameMeta meta;
    for (int k = 0; src->capture(raw.view(), meta, std::chrono::milliseconds(100)) == drivers::CaptureStatus::Frame; ++k) {
      const daemon::RectifyResult res = rect.process(raw.view(), rectified.view(), meta, buf);
      if (k < 2 || k % 2 || !res.rectified) continue;
      render_truth(meta.first_row_ns * 1e-9 + res.reference_time_s, truth.view());
      double frame_sum = 0;
      int frame_n = 0;
      add_shifts(cv::Mat(kH, kW, CV_8UC1, truth.data.data()), cv::Mat(kH, kW, CV_8UC1, rectified.data.data()), frame_sum, frame_n);
      sum += frame_sum, n += frame_n;
      if (frame_n) out.t.push_back(meta.first_row_ns * 1e-9), out.frame_rms.push_back(std::sqrt(frame_sum / frame_n));
    }
  }
  lcm_destroy(lcm);
  EXPECT_GT(n, 500);
  out.rms = n ? std::sqrt(sum / n) : INFINITY;
  return out;
}

// An images recording played as the daemon plays it (rsd --replay DIR --speed fast).
daemon::Config replay_of(const fs::path& dir) {
  daemon::Config cfg;
  cfg.source.driver = "recording";
  cfg.source.settings_of<drivers::RecordingReplayConfig>("recording").dir = dir.string();
  cfg.source.settings_of<drivers::RecordingReplayConfig>("recording").speed = 0;
  return cfg;
}

formats::Calibration learn(const fs::path& dir, const char* name) {
  const formats::ImagesRecording images = formats::read_images_recording(dir.string());
  const dsp::Recording obs = tools::observations_from_pictures(images, dsp::TrackOptions{});
  const dsp::Diagnosis d = dsp::diagnose(obs);
  const std::string cal_file = (dir / "cal.yaml").string();
  formats::write_calibration(cal_file, tools::calibration_from(obs, d, "closed-loop test"));
  const formats::Calibration learned = formats::read_calibration(cal_file);
  std::printf("[%s] %zu matches, baseline %.3f px, sigma %.3f, final %.3f px; named:", name, obs.matches.size(),
              d.baseline.rms_px, d.sigma_px, d.final_rms_px);
  for (const auto& e : d.effects) {
    std::printf(" %s(", e.name.c_str());
    for (const auto& q : e.params) std::printf("%s=%.4g ", q.name.c_str(), q.value);
    std::printf(")");
  }
  std::printf("\n  learned: f %.2f, line delay %.4g, offset %.5f, bias (%.4f %.4f %.4f)\n", learned.cam.fx,
              learned.line_delay_s, learned.timeshift_cam_imu_s, learned.gyro_bias_rad_s.x(), learned.gyro_bias_rad_s.y(),
              learned.gyro_bias_rad_s.z());
  return learned;
}

formats::Calibration true_calibration(const drivers::SimSourceConfig& t, const dsp::NominalModel& nominal) {
  formats::Calibration c = formats::calibration_of(nominal, "truth");
  c.cam = t.camera;
  c.line_delay_s = t.line_delay_s;
  c.timeshift_cam_imu_s = t.imu_time_offset_s;
  c.gyro_bias_rad_s = t.gyro_bias;
  c.imu_to_camera = dsp::exp_so3(t.imu_mount_rotation_rad);
  return c;
}

SimTruth::SimTruth(const SimRig& r, int64_t t0_ns) : sim_(r.truth), t0_s_(static_cast<double>(t0_ns) * 1e-9) {
  sim_.open();
  dsp::RowTiming global = sim_.timing();
  global.line_delay_s = 1e-12;  // every row at once
  dsp::RenderOptions ro;
  ro.supersample = 2;
  gs_ = std::make_unique<dsp::RsRenderer>(r.truth.camera, global, ro);
}

void SimTruth::operator()(double t, const dsp::ImageView& v) { gs_->render(sim_.scene(), sim_.truth(), t - t0_s_, v); }

}  // namespace rsd::test
