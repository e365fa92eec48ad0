// GoPro's GPMF gyro (formats/gpmf.hpp): payloads written here byte by byte from the published
// layout (an independent writer), GoPro's own sample payloads (tests/data/real/gpmf, their values
// decoded by a separate script, tests/data/real/gpmf/gyro_dump.py), and damaged payloads refused
// naming the byte and the key.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "formats/gpmf.hpp"
#include "formats/gpmf_mp4.hpp"
#include "formats/video_file.hpp"
#include "tests/support/temp_dir.hpp"

namespace rsd::formats::test_gpmf {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

using Bytes = std::vector<std::uint8_t>;

const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_gpmf_");

// One KLV item: key, type, structure size, repeat (big-endian), data padded to four bytes.
Bytes klv(const char* key, char type, int struct_size, int repeat, const Bytes& data) {
  Bytes b(key, key + 4);
  b.push_back(static_cast<std::uint8_t>(type));
  b.push_back(static_cast<std::uint8_t>(struct_size));
  b.push_back(static_cast<std::uint8_t>(repeat >> 8));
  b.push_back(static_cast<std::uint8_t>(repeat & 0xff));
  b.insert(b.end(), data.begin(), data.end());
  while (b.size() % 4) b.push_back(0);
  return b;
}

Bytes nest(const char* key, const std::vector<Bytes>& items) {
  Bytes inner;
  for (const Bytes& i : items) inner.insert(inner.end(), i.begin(), i.end());
  return klv(key, 0, 1, static_cast<int>(inner.size()), inner);
}

Bytes be16(std::initializer_list<int> v) {
  Bytes b;
  for (int x : v) b.push_back(static_cast<std::uint8_t>(static_cast<std::uint16_t>(x) >> 8)), b.push_back(static_cast<std::uint8_t>(x & 0xff));
  return b;
}

Bytes be32(std::initializer_list<std::int64_t> v) {
  Bytes b;
  for (std::int64_t x : v)
    for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<std::uint8_t>(static_cast<std::uint32_t>(x) >> s));
  return b;
}

Bytes text(const std::string& s) { return Bytes(s.begin(), s.end()); }

std::vector<GpmfGyro> read(const Bytes& b) { return read_gpmf_gyro(b.data(), b.size(), "payload 7"); }

std::string error_of(const Bytes& b) {
  try {
    read(b);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no error";
}

// A camera device with an accelerometer stream and a gyro stream, as GoPro's cameras write them.
Bytes camera_payload(const Bytes& gyro_scal, const Bytes& gyro) {
  return nest("DEVC", {klv("DVID", 'L', 4, 1, be32({1})), klv("DVNM", 'c', 6, 1, text("Camera")),
                       nest("STRM", {klv("TSMP", 'L', 4, 1, be32({2})), klv("SCAL", 's', 2, 1, be16({418})),
                                     klv("ACCL", 's', 6, 2, be16({418, 0, 0, 0, 418, 0}))}),
                       nest("STRM", {klv("STMP", 'J', 8, 1, Bytes{0, 0, 0, 0, 0x04, 0xe2, 0x31, 0x5e}),
                                     klv("TSMP", 'L', 4, 1, be32({392})), klv("SIUN", 'c', 5, 1, text("rad/s")),
                                     klv("ORIN", 'c', 3, 1, text("ZXY")), gyro_scal, gyro})});
}

TEST(Gpmf, TheGyroStreamIsReadScaledWithItsStickyKeys) {
  const Bytes p = camera_payload(klv("SCAL", 's', 2, 1, be16({100})), klv("GYRO", 's', 6, 2, be16({150, -200, 0, -32768, 32767, 1})));
  const std::vector<GpmfGyro> g = read(p);
  ASSERT_EQ(g.size(), 1u);  // the accelerometer is not a gyro
  ASSERT_EQ(g[0].rate_rad_s.size(), 2u);
  EXPECT_EQ(g[0].rate_rad_s[0], Eigen::Vector3d(1.5, -2.0, 0.0));
  EXPECT_EQ(g[0].rate_rad_s[1], Eigen::Vector3d(-327.68, 327.67, 0.01));
  EXPECT_EQ(g[0].orin, "ZXY");
  EXPECT_EQ(g[0].siun, "rad/s");
  EXPECT_EQ(g[0].device, "Camera");
  EXPECT_EQ(g[0].tsmp, 392u);
  EXPECT_EQ(g[0].stmp_us, 81932638u);  // 0x04e2315e
}

TEST(Gpmf, OneDivisorPerAxisAndFloatSamples) {
  const Bytes per_axis = camera_payload(klv("SCAL", 'l', 12, 1, be32({10, 100, 1000})), klv("GYRO", 's', 6, 1, be16({5, 5, 5})));
  EXPECT_EQ(read(per_axis).at(0).rate_rad_s.at(0), Eigen::Vector3d(0.5, 0.05, 0.005));
  // 0.25f = 0x3e800000, -2.0f = 0xc0000000, 8.0f = 0x41000000
  const Bytes floats = camera_payload(klv("SCAL", 's', 2, 1, be16({1})),
                                      klv("GYRO", 'f', 12, 1, be32({0x3e800000, 0xc0000000, 0x41000000})));
  EXPECT_EQ(read(floats).at(0).rate_rad_s.at(0), Eigen::Vector3d(0.25, -2.0, 8.0));
}

TEST(Gpmf, DamagedPayloadsAreRefusedNamingTheByteAndTheKey) {
  const Bytes good = camera_payload(klv("SCAL", 's', 2, 1, be16({100})), klv("GYRO", 's', 6, 2, be16({1, 2, 3, 4, 5, 6})));
  // The DEVC claims more bytes than the payload holds.
  Bytes cut(good.begin(), good.end() - 8);
  EXPECT_NE(error_of(cut).find("payload 7: byte 0: 'DEVC' holds"), std::string::npos) << error_of(cut);
  // A header cut short.
  const Bytes stub = {'D', 'E', 'V'};
  EXPECT_NE(error_of(stub).find("byte 0 is a truncated item header (3 bytes left, 8 needed)"), std::string::npos) << error_of(stub);
  // Two axes, a zero divisor, no divisor, a key that is not text.
  const Bytes two_axes = camera_payload(klv("SCAL", 's', 2, 1, be16({100})), klv("GYRO", 's', 4, 1, be16({1, 2})));
  EXPECT_NE(error_of(two_axes).find("'GYRO' samples are 4 bytes of type 's': a gyro sample is three axes"), std::string::npos)
      << error_of(two_axes);
  const Bytes zero = camera_payload(klv("SCAL", 's', 2, 1, be16({0})), klv("GYRO", 's', 6, 1, be16({1, 2, 3})));
  EXPECT_NE(error_of(zero).find("'GYRO' has a SCAL of 0"), std::string::npos) << error_of(zero);
  const Bytes none = nest("DEVC", {nest("STRM", {klv("GYRO", 's', 6, 1, be16({1, 2, 3}))})});
  EXPECT_NE(error_of(none).find("byte 16: 'GYRO' has no SCAL before it"), std::string::npos) << error_of(none);
  const Bytes binary = nest("DEVC", {klv("\x01\x02\x03\x04", 'L', 4, 1, be32({1}))});
  EXPECT_NE(error_of(binary).find("byte 8 is not a GPMF key"), std::string::npos) << error_of(binary);
  // A sample count or time stamp no integer can hold (a float TSMP of 5e10, a negative STMP): the
  // fuzzer's find (tests/fuzz/corpus/gpmf/crash-5af7dc8e...), refused instead of converted.
  const Bytes huge = nest("DEVC", {nest("STRM", {klv("TSMP", 'f', 4, 1, Bytes{0x51, 0x42, 0x00, 0x00})})});
  EXPECT_NE(error_of(huge).find("'TSMP' holds 52076478464.000000: not a whole number from 0 to 4294967295"), std::string::npos)
      << error_of(huge);
  const Bytes negative = nest("DEVC", {nest("STRM", {klv("STMP", 'l', 4, 1, be32({-5}))})});
  EXPECT_NE(error_of(negative).find("'STMP' holds -5.000000: not a whole number"), std::string::npos) << error_of(negative);
  // Zero padding after the last item ends the list; what rsd does not know is skipped.
  Bytes padded = good;
  padded.insert(padded.end(), 8, 0);
  EXPECT_EQ(read(padded).at(0).rate_rad_s.size(), 2u);
  EXPECT_TRUE(read(klv("XXXX", 'l', 4, 3, be32({1, 2, 3}))).empty());
}

Bytes real_payload(const std::string& name) {
  std::ifstream in(std::string(RSD_REAL_DATA_DIR) + "/gpmf/" + name, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), {});
}

// GoPro's sample payloads (gpmf-parser's samples/*.raw). The values are gyro_dump.py's raw
// integers (python3 tests/data/real/gpmf/gyro_dump.py tests/data/real/gpmf/*.raw) over the SCAL.
TEST(Gpmf, GoProsSamplePayloadsReadAsPublished) {
  struct Case {
    const char* file;
    std::size_t samples;
    Eigen::Vector3d first, last;
    std::optional<std::uint64_t> stmp;
  };
  const Case cases[] = {
      {"karma.raw", 392, {172 / 3755.0, 70 / 3755.0, 125 / 3755.0}, {268 / 3755.0, 83 / 3755.0, -5 / 3755.0}, {}},
      {"hero5.raw", 399, {185 / 3755.0, 153 / 3755.0, 105 / 3755.0}, {-1779 / 3755.0, -548 / 3755.0, 263 / 3755.0}, {}},
      {"hero6.raw", 204, {-1211 / 1878.0, -345 / 1878.0, -508 / 1878.0}, {11 / 1878.0, -63 / 1878.0, -98 / 1878.0}, {}},
      {"Fusion.raw", 3300, {-249 / 939.0, 312 / 939.0, -432 / 939.0}, {45 / 939.0, 123 / 939.0, -215 / 939.0}, 82006526u},
  };
  for (const Case& c : cases) {
    const Bytes p = real_payload(c.file);
    ASSERT_FALSE(p.empty()) << c.file;
    const std::vector<GpmfGyro> g = read_gpmf_gyro(p.data(), p.size(), c.file);
    ASSERT_EQ(g.size(), 1u) << c.file;
    EXPECT_EQ(g[0].rate_rad_s.size(), c.samples) << c.file;
    EXPECT_EQ(g[0].siun, "rad/s") << c.file;
    EXPECT_EQ(g[0].rate_rad_s.front(), c.first) << c.file;
    EXPECT_EQ(g[0].rate_rad_s.back(), c.last) << c.file;
    EXPECT_EQ(g[0].stmp_us, c.stmp) << c.file;
  }
}

// A whole recording: the Karma drone's gimbal camera (a HERO5 Black, 12 s at 854x480). The first
// payload is karma.raw; the frames are as many as OpenCV's decoder finds; the gyro is GoPro's 400 Hz
// nominal rate, spread over the payloads' spans on the MP4's clock.
TEST(GpmfVideo, TheKarmaClipsGyroAndFramesOnTheMp4sClock) {
  const std::string file = std::string(RSD_REAL_DATA_DIR) + "/gpmf/karma.mp4";
  const GpmfVideo v = read_gpmf_video(file);
  EXPECT_EQ(v.width, 854);
  EXPECT_EQ(v.height, 480);
  EXPECT_EQ(v.payloads, 13);
  EXPECT_EQ(v.device, "Camera");
  EXPECT_EQ(v.orin, "");  // a HERO5 writes none: its order is documented (Z, X, Y)
  // The first payload's samples, read from the MP4, are karma.raw's.
  const Bytes raw = real_payload("karma.raw");
  const std::vector<GpmfGyro> first = read_gpmf_gyro(raw.data(), raw.size(), "karma.raw");
  ASSERT_GE(v.gyro_rad_s.size(), first.at(0).rate_rad_s.size());
  for (std::size_t i = 0; i < first[0].rate_rad_s.size(); ++i) ASSERT_EQ(v.gyro_rad_s[i], first[0].rate_rad_s[i]) << i;
  // Times rise; the rate is GoPro's nominal 400 Hz within the 1% its clocks keep.
  for (std::size_t i = 1; i < v.gyro_t_s.size(); ++i) ASSERT_GT(v.gyro_t_s[i], v.gyro_t_s[i - 1]) << i;
  const double rate = static_cast<double>(v.gyro_t_s.size() - 1) / (v.gyro_t_s.back() - v.gyro_t_s.front());
  EXPECT_NEAR(rate, 400, 4) << rate;
  // Every frame a decoder finds has its time, 30000/1001 frames a second apart.
  VideoReader decoder(file);
  dsp::Image frame;
  long decoded = 0;
  while (decoder.next(frame)) ++decoded;
  EXPECT_EQ(static_cast<long>(v.frame_t_s.size()), decoded);
  for (std::size_t k = 1; k < v.frame_t_s.size(); ++k) ASSERT_NEAR(v.frame_t_s[k] - v.frame_t_s[k - 1], 1001.0 / 30000, 1e-4) << k;
  // The gyro covers the frames.
  EXPECT_LE(v.gyro_t_s.front(), v.frame_t_s.front());
  EXPECT_GE(v.gyro_t_s.back(), v.frame_t_s.back());
}

TEST(GpmfVideo, FilesWithoutAGoProsTracksAreRefusedNamingThem) {
  const std::string plain = g_tmp.path("plain.mp4");
  {
    VideoWriter w(plain, 64, 48, 30);
    dsp::Image f(64, 48, dsp::PixelFormat::Mono8);
    for (int k = 0; k < 3; ++k) w.write(f.view());
  }
  auto error_of_file = [](const std::string& path) -> std::string {
    try {
      read_gpmf_video(path);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_EQ(error_of_file(plain), plain + ": no GPMF metadata track (a GoPro camera's 'gpmd' data stream)");
  const std::string not_video = std::string(RSD_REAL_DATA_DIR) + "/gpmf/karma.raw";
  EXPECT_NE(error_of_file(not_video).find(not_video + ": cannot open as an MP4: "), std::string::npos) << error_of_file(not_video);
}

}  // namespace
}  // namespace rsd::formats::test_gpmf
