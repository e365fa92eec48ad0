// The diagnosis on real recordings (tests/data/real, their sources in its README), run as a user
// would: rsd-extract turns the camera's files into an images recording, rsd-diagnose diagnoses
// it. Issue 34's invariants must hold on each: the final model predicts the held-out frames no
// worse than the nominal model, and nothing named has a value real hardware does not have (the
// limits below are the hardware's, written here apart from the diagnosis's own plausibility
// module). What each scene shows is asserted where it is known.
#include <algorithm>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "daemon/config.hpp"
#include "daemon/service.hpp"
#include "drivers/recording_replay_source.hpp"
#include "dsp/diagnosis/diagnosis.hpp"
#include "formats/calibration_v1.hpp"
#include "formats/recording_v1.hpp"
#include "tests/support/diagnosis_verdict.hpp"
#include "tools/common/picture_observations.hpp"

using namespace rsd;
using namespace rsd::test;

namespace {

const std::string kData = RSD_REAL_DATA_DIR;
const std::string kWork = RSD_REAL_WORK_DIR;

struct Nominal {
  double fx, fy, frame_rate_hz;
  int height;
};

// Values a real camera and a MEMS gyro have: a bias within 0.1 rad/s, a gyro scale within 5% of
// one, a focal length within 25% of the calibrated one with square pixels (1%), a readout within
// the frame period, a clock offset within a second.
void expect_plausible(const Verdict& v, const Nominal& n, const std::string& json) {
  for (const auto& [name, p] : v.params) {
    if (name == "gyro_bias") {
      EXPECT_LT(std::hypot(p.at("bx"), p.at("by"), p.at("bz")), 0.1) << json;
    } else if (name == "gyro_scale") {
      for (const char* k : {"sx", "sy", "sz"}) EXPECT_NEAR(p.at(k), 1.0, 0.05) << k << "\n" << json;
    } else if (name == "focal_length") {
      EXPECT_NEAR(p.at("fx") / n.fx, 1.0, 0.25) << json;
      EXPECT_NEAR(p.at("fy") / n.fy, 1.0, 0.25) << json;
      EXPECT_NEAR(p.at("fx") / p.at("fy"), n.fx / n.fy, 0.01) << json;
    } else if (name == "rolling_shutter") {
      EXPECT_LT(p.at("line_delay_s") * n.height, 1.0 / n.frame_rate_hz) << json;
    } else if (name == "time_offset") {
      EXPECT_LT(std::abs(p.at("time_offset_s")), 1.0) << json;
    }
  }
}

void expect_invariants(const Verdict& v, const Nominal& n, const std::string& json) {
  ASSERT_TRUE(std::isfinite(v.heldout_baseline_rms_px) && std::isfinite(v.heldout_final_rms_px)) << json;
  EXPECT_LE(v.heldout_final_rms_px, v.heldout_baseline_rms_px) << json;
  // Nothing named, the final model is the nominal one (a focal length withdrawn on the GoPro MAX
  // clip once left fy 26% off, which predicted the held-out frames 6% better than the nominal).
  if (v.effects.empty()) {
    EXPECT_EQ(v.heldout_final_rms_px, v.heldout_baseline_rms_px) << json;
  }
  // Half by half in time: a named effect must not make either half's prediction worse (by over 2%).
  for (int h = 0; h < 2; ++h) {
    ASSERT_TRUE(std::isfinite(v.half_baseline_rms_px[h]) && std::isfinite(v.half_final_rms_px[h])) << json;
    EXPECT_LE(v.half_final_rms_px[h], 1.02 * v.half_baseline_rms_px[h]) << "half " << h << "\n" << json;
  }
  expect_plausible(v, n, json);
}

}  // namespace

// A phone on a car's dashboard (phone-cc9: 800x600 Motion-JPEG, the phone's frame times and its
// 412 Hz gyro, the source's calibration and axes). The car drives forward past a near bus: the
// rotation-only model of matches cannot express that parallax, and an honest diagnosis says so
// (a significant remainder in translation) instead of naming a stand-in for it (a gyro bias of
// two thirds of a radian per second did, before the invariants).
TEST(RealRecordings, PhoneOnADashboardKeepsTheInvariantsAndSaysTheParallax) {
  const std::string src = kData + "/phone-cc9", dir = kWork + "/phone-cc9";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  must_run(std::string(RSD_EXTRACT) + " " + src + "/video.avi " + dir + "/rec --frame-times " + src +
               "/framestamp.txt --gyro-csv " + src + "/gyro.txt --gyro-columns wx,wy,wz,t --first-frame-index 98 --nominal " +
               src + "/nominal.yaml --imu-to-camera 0,-1,0,-1,0,0,0,0,-1",
           dir + "/extract.txt");
  must_run(std::string(RSD_DIAGNOSE) + " " + dir + "/rec --json " + dir + "/diagnosis.json", dir + "/diagnose.txt");
  const std::string json = slurp(dir + "/diagnosis.json");
  const Verdict v = read_verdict(dir + "/diagnosis.json");
  expect_invariants(v, {573.85, 575.04, 30.0, 600}, json);
  EXPECT_TRUE(v.remainder_significant) << json;
  ASSERT_FALSE(v.remainder_located.empty()) << json;
  EXPECT_EQ(v.remainder_located.front(), "translation") << json;
}

namespace {

// An images recording of a GoPro clip, made by rsd-extract from the MP4 with a guessed
// equidistant lens (f 400 px unless `focal_px` says otherwise), in the work directory `clip` +
// `suffix`; its path.
std::string gopro_images(const std::string& clip, int width, const std::string& suffix, double focal_px = 400) {
  const std::string dir = kWork + "/" + clip + suffix;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  {
    std::ofstream nominal(dir + "/nominal.yaml");
    nominal << "camera: {width: " << width << ", height: 480, fx: " << focal_px << ", fy: " << focal_px
            << ", cx: " << (width - 1) / 2.0
            << ", cy: 239.5, model: pinhole-equi, distortion: [0, 0, 0, 0]}\n";
  }
  must_run(std::string(RSD_EXTRACT) + " " + kData + "/gpmf/" + clip + ".mp4 " + dir + "/rec --nominal " + dir + "/nominal.yaml",
           dir + "/extract.txt");
  return dir + "/rec";
}

// GoPro clips (tests/data/real/gpmf), extracted from the MP4 with its GPMF gyro and a guessed
// equidistant lens (f 400 px: no calibration comes with them), the gyro's axes searched from the
// pictures. Neither holds a rotation the table can tell from what it sees: the Karma drone's
// gimbal keeps its camera nearly still through a forward flight (parallax), the MAX's video
// does not follow its gyro closely (2.8 px against 1 px of noise): the MAX stabilises its video
// in HERO mode, and the pictures follow its gyro smoothed over about 0.3 s (robust chi-square 40%
// lower), which the remainder says first; the gimbal's camera is not stabilised after its gyro,
// and its remainder must not say so. Each must keep the invariants and report a significant
// remainder, not name a stand-in; and each is diagnosed in seconds (issue 34, point 5: both took
// minutes before).
void expect_gopro_clip_honest(const std::string& clip, int width, bool stabilised) {
  const std::string rec = gopro_images(clip, width, ""), dir = kWork + "/" + clip;
  must_run(std::string(RSD_DIAGNOSE) + " " + rec + " --imu-axes search --json " + dir + "/diagnosis.json",
           dir + "/diagnose.txt");
  const std::string json = slurp(dir + "/diagnosis.json");
  const Verdict v = read_verdict(dir + "/diagnosis.json");
  expect_invariants(v, {400, 400, 29.97, 480}, json);
  EXPECT_TRUE(v.remainder_significant) << json;
  const auto& at = v.remainder_located;
  if (stabilised) {
    ASSERT_FALSE(at.empty()) << json;
    EXPECT_EQ(at.front(), "stabilisation") << json;
  } else {
    EXPECT_EQ(std::find(at.begin(), at.end(), "stabilisation"), at.end()) << json;
  }
}

}  // namespace

TEST(RealRecordings, KarmaDroneGimbalClipKeepsTheInvariants) { expect_gopro_clip_honest("karma", 854, false); }

TEST(RealRecordings, GoProMaxClipKeepsTheInvariants) { expect_gopro_clip_honest("max-heromode", 848, true); }

namespace {

// A copy of the matches recording `from` in `to` with its gyro's times moved by `move_s` (the
// motion clock late by that much: t_motion = t_camera + offset, so the offset moves with it).
void copy_with_gyro_moved(const std::string& from, const std::string& to, double move_s) {
  std::filesystem::remove_all(to);
  std::filesystem::copy(from, to);
  std::ifstream in(from + "/gyro.csv");
  std::ofstream out(to + "/gyro.csv");
  std::string line;
  std::getline(in, line);
  out << line << "\n";  // the header
  while (std::getline(in, line)) {
    const size_t comma = line.find(',');
    char t[32];
    std::snprintf(t, sizeof t, "%.17g", std::stod(line.substr(0, comma)) + move_s);
    out << t << line.substr(comma) << "\n";
  }
}

}  // namespace

// Issue 34: "a forward-flying drone with a pan must still yield its clock offset". The Karma
// clip is such a flight: the gimbal holds the camera still for 11 s and turns it in the last
// half second, so its clock shows in the pan's first frames alone, while the flight's parallax
// fills every pair. Its own offset is not known, so its gyro is moved 50 ms either way: both
// offsets must be named, 100 ms apart, and the invariants hold. (Before, the gross search put a
// wrong start 45 ms off, and the local fits did not cross the translation's jagged cost to the
// pan's valley; a clock drift of 3755 ppm stood in; and the blocked halves dropped the offset
// for what it did to the flight's outliers.) The nominal focal length is 540 px, what the pan's
// image turn against the gyro's gives: the guessed 400 is 35% short, and the drone came
// with its focal length right.
TEST(RealRecordings, KarmaClipsClockMovedEitherWayIsNamedWithTheMove) {
  const std::string images = gopro_images("karma", 854, "-moved", 540), dir = kWork + "/karma-moved";
  must_run(std::string(RSD_EXTRACT) + " " + images + " " + dir + "/matches", dir + "/extract-matches.txt");
  double offset[2] = {NAN, NAN};
  const double moves[2] = {-0.05, 0.05};
  for (int k = 0; k < 2; ++k) {
    const std::string moved = dir + (k ? "/late" : "/early");
    copy_with_gyro_moved(dir + "/matches", moved, moves[k]);
    must_run(std::string(RSD_DIAGNOSE) + " " + moved + " --imu-axes given --json " + moved + ".json", moved + ".txt");
    const std::string json = slurp(moved + ".json");
    const Verdict v = read_verdict(moved + ".json");
    expect_invariants(v, {540, 540, 29.97, 480}, json);
    ASSERT_TRUE(v.params.count("time_offset")) << json;
    offset[k] = v.params.at("time_offset").at("time_offset_s");
  }
  EXPECT_NEAR(offset[1] - offset[0], moves[1] - moves[0], 2e-3) << offset[0] << " and " << offset[1];
}

namespace {

// A value the offline diagnosis gives: a named effect's parameter with its sigma, or, where it
// names nothing, the nominal (known exactly: the diagnosis says the data need no other).
struct Offline {
  double value, sigma;
  bool named;
};
Offline offline_value(const dsp::Diagnosis& d, const std::string& effect, const std::string& param, double nominal) {
  for (const dsp::ParamUncertainty& u : d.uncertainties)
    if (u.effect == effect && u.param == param) return {u.value, u.sigma.value_or(0.0), true};
  return {nominal, 0.0, false};
}

// Issue 36, point 4: a learned value agrees with the diagnosis's within three combined sigmas; a
// value the diagnosis does not name is not learned away from the nominal.
void expect_agree(const char* what, const dsp::ValueNote& note, double online, double online_sigma, const Offline& off) {
  std::printf("[online vs offline] %s: online %.6g +- %.3g (%s), offline %.6g +- %.3g (%s)\n", what, online, online_sigma,
              dsp::to_string(note.status), off.value, off.sigma, off.named ? "named" : "not named: the nominal");
  if (note.status != dsp::ValueStatus::Learned) return;
  EXPECT_LE(std::abs(online - off.value), 3 * std::hypot(online_sigma, off.sigma)) << what;
}

// Issue 36, point 4, on an images recording `dir` that rsd-extract made as a user would: the
// diagnosis of its pictures, then the daemon replaying it in real time (as a camera) with the
// recording's nominal model and calibration.online: observe. What the estimator reports as
// learned agrees with the diagnosis; where the diagnosis names nothing the estimator learns
// nothing either, and says why.
void expect_online_agrees_with_the_diagnosis(const std::string& dir) {
  const formats::ImagesRecording images = formats::read_images_recording(dir);
  const dsp::Recording obs = tools::observations_from_pictures(images, dsp::TrackOptions{});
  const dsp::Diagnosis d = dsp::diagnose(obs);
  const dsp::NominalModel& n = obs.nominal;

  daemon::Config cfg;
  cfg.source.driver = "recording";
  cfg.source.settings_of<drivers::RecordingReplayConfig>("recording").dir = dir;
  cfg.source.settings_of<drivers::RecordingReplayConfig>("recording").speed = 1;  // real time, as a camera
  daemon::apply_calibration(cfg, formats::calibration_of(n, "nominal"));
  cfg.online.mode = daemon::OnlineMode::Observe;
  daemon::StopFlags flags;
  daemon::RunLimits limits;
  limits.status_line = false;
  daemon::RunSummary run;
  daemon::run_service(cfg, flags, limits, {}, &run);
  ASSERT_TRUE(run.online.has_value());
  const dsp::OnlineEstimate& e = *run.online;
  std::printf("[online] %s after %d updates: %s\n", dsp::to_string(e.state), e.updates, e.reason.c_str());

  expect_agree("time offset (s)", e.notes.time_offset, e.value.time_offset_s, e.sigma.time_offset_s,
               offline_value(d, "time_offset", "time_offset_s", n.time.time_offset_s));
  expect_agree("line delay (s)", e.notes.line_delay, e.value.line_delay_s, e.sigma.line_delay_s,
               offline_value(d, "rolling_shutter", "line_delay_s", n.time.line_delay_s));
  const char* axes[] = {"bx", "by", "bz"};
  for (int i = 0; i < 3; ++i)
    expect_agree(axes[i], e.notes.gyro_bias, e.value.gyro_bias[i], e.sigma.gyro_bias[i], offline_value(d, "gyro_bias", axes[i], 0.0));
  if (d.effects.empty()) {
    for (const dsp::ValueNote* v : {&e.notes.time_offset, &e.notes.line_delay, &e.notes.gyro_bias})
      EXPECT_NE(v->status, dsp::ValueStatus::Learned);
    EXPECT_FALSE(e.converged);
    EXPECT_FALSE(e.reason.empty());
  }
}

}  // namespace

// A real phone on a car's dashboard (tests/data/real/phone-cc9, its sources in the README there).
// The car drives forward past a near bus: the diagnosis names nothing (its remainder says the
// parallax, RealRecordings.*); the estimator must not learn anything else from the same
// pictures, and it holds for the parallax.
TEST(RealRecordings, PhoneOnADashboardOnlineCalibrationAgreesWithTheDiagnosis) {
  const std::string src = kData + "/phone-cc9";
  const std::string dir = kWork + "/phone-cc9-online";
  std::filesystem::remove_all(dir);
  const std::string extract = std::string(RSD_EXTRACT) + " " + src + "/video.avi " + dir + " --frame-times " + src +
                              "/framestamp.txt --gyro-csv " + src + "/gyro.txt --gyro-columns wx,wy,wz,t --first-frame-index 98 " +
                              "--nominal " + src + "/nominal.yaml --imu-to-camera 0,-1,0,-1,0,0,0,0,-1 > /dev/null";
  ASSERT_EQ(std::system(extract.c_str()), 0) << extract;
  expect_online_agrees_with_the_diagnosis(dir);
}

// The GoPro clips (tests/data/real/gpmf), made images recordings from their MP4s with the same
// guessed lens as their diagnosis tests: a user's first configuration, no line delay, no offset
// (issue 36's "unknown readout"). The Karma drone's gimbal camera in forward flight and the
// MAX's video, which does not follow its gyro closely: the diagnosis names nothing on either.
TEST(RealRecordings, KarmaDroneGimbalClipOnlineCalibrationAgreesWithTheDiagnosis) {
  expect_online_agrees_with_the_diagnosis(gopro_images("karma", 854, "-online"));
}

TEST(RealRecordings, GoProMaxClipOnlineCalibrationAgreesWithTheDiagnosis) {
  expect_online_agrees_with_the_diagnosis(gopro_images("max-heromode", 848, "-online"));
}
