// Gyroflow's .gcsv gyro logs (formats/gcsv.hpp) on hand-made files: the header's scales and
// optional timing, samples in raw integers and in floating point, times in s from tscale and
// rates in rad/s from gscale (worked by hand below); damaged files refused naming the file, the
// line and the key or column. A video's frame times (formats/video_frame_times.hpp) from the
// phone recording's Motion-JPEG AVI, against its frame rate.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "formats/gcsv.hpp"
#include "formats/video_frame_times.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

namespace rsd::formats::test_gcsv {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_gcsv_");

std::string file_with(const std::string& name, const std::string& text) { return g_tmp.file_with(name, text); }
using test::error_of;

const std::string kHeader =
    "GYROFLOW IMU LOG\n"
    "version,1.3\n"
    "id,test_rig\n"
    "orientation,XYZ\n"
    "note,made by hand, with a comma\n"
    "frame_readout_time,20.5\n"
    "frame_readout_direction,1\n"
    "tscale,0.001\n"
    "gscale,0.002\n"
    "ascale,0.0005\n";

TEST(Gcsv, ScalesTheRawIntegersIntoSecondsAndRadiansPerSecond) {
  const GcsvLog g = read_gcsv(file_with("a.gcsv", kHeader + "t,gx,gy,gz,ax,ay,az\n0,100,-50,7,1,2,3\n5,-1,0,1000,1,2,3\r\n"));
  EXPECT_EQ(g.version, "1.3");
  EXPECT_EQ(g.id, "test_rig");
  EXPECT_EQ(g.orientation, "XYZ");
  ASSERT_TRUE(g.frame_readout_s);
  EXPECT_DOUBLE_EQ(*g.frame_readout_s, 0.0205);  // 20.5 ms
  EXPECT_EQ(g.readout_direction, 1);
  ASSERT_EQ(g.gyro.size(), 2u);
  EXPECT_DOUBLE_EQ(g.gyro[0].t, 0.0);
  EXPECT_DOUBLE_EQ(g.gyro[1].t, 0.005);  // 5 x 0.001 s
  EXPECT_DOUBLE_EQ(g.gyro[0].w.x(), 0.2);  // 100 x 0.002 rad/s
  EXPECT_DOUBLE_EQ(g.gyro[0].w.y(), -0.1);
  EXPECT_DOUBLE_EQ(g.gyro[0].w.z(), 0.014);
  EXPECT_DOUBLE_EQ(g.gyro[1].w.z(), 2.0);
}

TEST(Gcsv, TheNeutralFirstLineFloatingPointAndNoOptionalKeys) {
  const GcsvLog g = read_gcsv(file_with("b.gcsv",
                                        "CAMERA IMU LOG\nversion,1.1\nid,x\norientation,YxZ\ntscale,1\ngscale,1\n"
                                        "t,gx,gy,gz\n-0.25,0.5,1e-3,-2\n\n0.75,0,0,0\n"));
  EXPECT_FALSE(g.frame_readout_s);
  EXPECT_FALSE(g.readout_direction);
  ASSERT_EQ(g.gyro.size(), 2u);
  EXPECT_DOUBLE_EQ(g.gyro[0].t, -0.25);
  EXPECT_DOUBLE_EQ(g.gyro[0].w.y(), 0.001);
  EXPECT_DOUBLE_EQ(g.gyro[1].t, 0.75);
}

TEST(Gcsv, DamagedLogsAreRefusedNamingTheLineAndTheKey) {
  const std::string ok_rows = "t,gx,gy,gz\n0,1,2,3\n1,1,2,3\n";
  struct Case {
    std::string text, says;
  };
  for (const Case& c : {
           Case{"IMU DATA\n" + ok_rows, ":1: not a gyroflow .gcsv log"},
           Case{"GYROFLOW IMU LOG\ntscale,0.001\n" + ok_rows, ":3: no 'gscale' line before the column header"},
           Case{"GYROFLOW IMU LOG\ntscale,fast\ngscale,1\n" + ok_rows, ":2: tscale 'fast' is not a number"},
           Case{"GYROFLOW IMU LOG\ntscale,-1\ngscale,1\n" + ok_rows, ":2: tscale must be positive"},
           Case{"GYROFLOW IMU LOG\ntscale,1\ngscale,1\nframe_readout_time,2500\n" + ok_rows, ":4: frame_readout_time must be at least 0 and under 1000"},
           Case{"GYROFLOW IMU LOG\ntscale,1\ngscale,1\nframe_readout_direction,4\n" + ok_rows,
                ":4: frame_readout_direction must be 0, 1, 2 or 3"},
           Case{"GYROFLOW IMU LOG\ntscale,1\ngscale,1\nt,ax,ay,az\n0,1,2,3\n1,1,2,3\n", ":4: the column header must start with t,gx,gy,gz"},
           Case{"GYROFLOW IMU LOG\ntscale,1\ngscale,1\nt,gx,gy,gz\n0,1,2,3\n1,1,x,3\n", ":6: column gy 'x' is not a number"},
           Case{"GYROFLOW IMU LOG\ntscale,1\ngscale,1\nt,gx,gy,gz\n0,1,2,3\n1,1,2\n", ":6: expected at least 4 fields"},
           Case{"GYROFLOW IMU LOG\ntscale,1\ngscale,1\nt,gx,gy,gz\n2,1,2,3\n1,1,2,3\n", ":6: time goes back (1 after 2)"},
           Case{"GYROFLOW IMU LOG\ntscale,1\ngscale,1\nt,gx,gy,gz\n2,1,2,3\n", "fewer than two gyro samples"},
           Case{"GYROFLOW IMU LOG\ntscale,1\ngscale,1\n", "no column header"},
       }) {
    const std::string path = file_with("bad.gcsv", c.text);
    const std::string e = error_of([&] { read_gcsv(path); });
    EXPECT_NE(e.find(path), std::string::npos) << e;
    EXPECT_NE(e.find(c.says), std::string::npos) << "expected '" << c.says << "' in: " << e;
  }
  EXPECT_NE(error_of([] { read_gcsv(g_tmp.path("missing.gcsv")); }).find("cannot open"), std::string::npos);
}

TEST(VideoFrameTimes, AThirtyFramesPerSecondAviFromZero) {
  const std::vector<double> t = read_video_frame_times(RSD_REAL_DATA_DIR "/phone-cc9/video.avi");
  ASSERT_EQ(t.size(), 103u);  // the README's count
  for (size_t k = 0; k < t.size(); ++k) EXPECT_NEAR(t[k], k / 30.0, 1e-9) << k;
  const std::string empty = file_with("empty.avi", "");
  EXPECT_NE(error_of([&] { read_video_frame_times(empty); }).find(empty + ": "), std::string::npos);
}

}  // namespace
}  // namespace rsd::formats::test_gcsv
