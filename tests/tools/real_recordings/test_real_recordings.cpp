// The diagnosis on real recordings (tests/data/real, their sources in its README), run as a user
// would: rsd-extract turns the camera's files into an images recording, rsd-diagnose diagnoses
// it. Issue 34's invariants must hold on each: the final model predicts the held-out frames no
// worse than the nominal model, and nothing named has a value real hardware does not have (the
// limits below are the hardware's, written here apart from the diagnosis's own plausibility
// module). What each scene shows is asserted where it is known.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "tests/support/diagnosis_verdict.hpp"

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
