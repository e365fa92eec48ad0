// A phone or logger's gyro columns and frame times (formats/sensor_csv.hpp): column orders, units,
// headers and separators; the phone recording in tests/data/real/phone-cc9 against the same
// samples as its source printed them in another format (gyro_dump.txt: microsecond stamps, six
// decimals); damaged files refused naming the file, the line and the column.
#include <gtest/gtest.h>

#include <string>

#include "formats/sensor_csv.hpp"
#include "tests/support/error_of.hpp"
#include "tests/support/temp_dir.hpp"

namespace rsd::formats::test_sensor_csv {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_sensor_csv_");

std::string file_with(const std::string& name, const std::string& text) { return g_tmp.file_with(name, text); }
using test::error_of;

TEST(SensorCsv, ColumnsInAnyOrderWithSkippedOnes) {
  const GyroColumns c = parse_gyro_columns("wx,wy,wz,t");
  EXPECT_EQ(c.index, (std::array<int, 4>{3, 0, 1, 2}));
  const GyroColumns s = parse_gyro_columns("t,-,-,wx,wy,wz");
  EXPECT_EQ(s.index, (std::array<int, 4>{0, 3, 4, 5}));
  EXPECT_EQ(s.count, 6);
  EXPECT_NE(error_of([] { parse_gyro_columns("t,wx,wy"); }).find("no column 'wz'"), std::string::npos);
  EXPECT_NE(error_of([] { parse_gyro_columns("t,wx,wy,wq"); }).find("'wq' is not t, wx, wy, wz or -"), std::string::npos);
  EXPECT_NE(error_of([] { parse_gyro_columns("t,wx,wy,wz,t"); }).find("'t' named twice"), std::string::npos);
}

TEST(SensorCsv, ReadsGyroWithAHeaderAnySeparatorAndAUnit) {
  const std::string p = file_with("g.csv",
                                  "timestamp_ns;gx;gy;gz;temperature\n"
                                  "# a comment\n"
                                  "1000000000;0.1;-0.2;0.3;25\n"
                                  "\n"
                                  "1002500000; 0.4 ;0.5;-0.6;25\n");
  const std::vector<dsp::GyroSample> g = read_gyro_csv(p, parse_gyro_columns("t,wx,wy,wz,-"), time_unit_seconds("ns"));
  ASSERT_EQ(g.size(), 2u);
  EXPECT_DOUBLE_EQ(g[0].t, 1.0);
  EXPECT_DOUBLE_EQ(g[1].t, 1.0025);
  EXPECT_EQ(g[0].w, Eigen::Vector3d(0.1, -0.2, 0.3));
  EXPECT_EQ(g[1].w, Eigen::Vector3d(0.4, 0.5, -0.6));
  const std::string spaces = file_with("g.txt", "0.1 0.2 0.3 5\n0.1\t0.2\t0.3\t6\n");
  EXPECT_EQ(read_gyro_csv(spaces, parse_gyro_columns("wx,wy,wz,t"), 1.0)[1].t, 6.0);
}

TEST(SensorCsv, FrameTimesOnePerLine) {
  const std::string p = file_with("f.txt", "t_ms\n1000\n1033.5\n1066.75\n");
  const std::vector<double> t = read_frame_times(p, time_unit_seconds("ms"));
  ASSERT_EQ(t.size(), 3u);
  EXPECT_DOUBLE_EQ(t[0], 1.0);
  EXPECT_DOUBLE_EQ(t[2], 1.06675);
}

TEST(SensorCsv, DamagedFilesAreRefusedNamingLineAndColumn) {
  const GyroColumns c = parse_gyro_columns("t,wx,wy,wz");
  const std::string bad = file_with("bad.csv", "t,wx,wy,wz\n1,0,0,0\n2,0,abc,0\n");
  EXPECT_NE(error_of([&] { read_gyro_csv(bad, c, 1.0); }).find("bad.csv:3: field 'wy' (column 3): 'abc' is not a number"),
            std::string::npos);
  const std::string short_line = file_with("short.csv", "1,0,0,0\n2,0,0\n");
  EXPECT_NE(error_of([&] { read_gyro_csv(short_line, c, 1.0); }).find("short.csv:2: 3 fields; the columns t,wx,wy,wz need 4"),
            std::string::npos);
  const std::string back = file_with("back.csv", "2,0,0,0\n1,0,0,0\n");
  EXPECT_NE(error_of([&] { read_gyro_csv(back, c, 1.0); }).find("back.csv:2: time 1 is before the previous sample's"),
            std::string::npos);
  const std::string one = file_with("one.csv", "1,0,0,0\n");
  EXPECT_NE(error_of([&] { read_gyro_csv(one, c, 1.0); }).find("fewer than two gyro samples"), std::string::npos);
  const std::string nan = file_with("nan.csv", "1,0,0,0\n2,nan,0,0\n");
  EXPECT_NE(error_of([&] { read_gyro_csv(nan, c, 1.0); }).find("nan.csv:2: field 'wx'"), std::string::npos);
  const std::string same = file_with("same.txt", "1\n2\n2\n");
  EXPECT_NE(error_of([&] { read_frame_times(same, 1.0); }).find("same.txt:3: frame time 2 is not after the previous frame's"),
            std::string::npos);
  EXPECT_NE(error_of([&] { read_frame_times(g_tmp.path("missing.txt"), 1.0); }).find("missing.txt: cannot open"),
            std::string::npos);
  EXPECT_NE(error_of([] { time_unit_seconds("min"); }).find("'min' is not s, ms, us or ns"), std::string::npos);
}

// The phone recording: gyro.txt (seconds, rad/s) holds what the phone's own dump printed
// (gyro_dump.txt in the source, not kept: microseconds and six decimals) for the first and last
// samples kept; framestamp.txt holds 2146 frames at 30 fps.
TEST(SensorCsv, ThePhoneRecordingReadsAsItsSourcePrintedIt) {
  const std::string dir = std::string(RSD_REAL_DATA_DIR) + "/phone-cc9";
  const std::vector<dsp::GyroSample> g = read_gyro_csv(dir + "/gyro.txt", parse_gyro_columns("wx,wy,wz,t"), 1.0);
  ASSERT_EQ(g.size(), 2225u);
  EXPECT_NEAR(g.front().t, 4328042692615e-6, 1e-6);  // "frameid:68 gyro:14 x 0.311849 y -0.399041 z -0.018819 ts 4328042692615"
  EXPECT_LE((g.front().w - Eigen::Vector3d(0.311849, -0.399041, -0.018819)).norm(), 1e-6);
  EXPECT_NEAR(g.back().t, 4328048088134e-6, 1e-6);  // "frameid:230 gyro:14 x 0.010081 y -0.112545 z 0.003172 ts 4328048088134"
  EXPECT_LE((g.back().w - Eigen::Vector3d(0.010081, -0.112545, 0.003172)).norm(), 1e-6);
  const std::vector<double> f = read_frame_times(dir + "/framestamp.txt", 1.0);
  ASSERT_EQ(f.size(), 2146u);
  EXPECT_NEAR((f.back() - f.front()) / 2145, 1 / 30.0, 1e-4);
}

}  // namespace
}  // namespace rsd::formats::test_sensor_csv
