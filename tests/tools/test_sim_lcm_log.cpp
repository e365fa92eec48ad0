// The simulator's LCM log: standard events that decode as libbot2-compatible image_t (same
// fingerprint as libbot2's) with per-row timing metadata, and rsd.velocity_t carrying the
// camera's true motion.
#include <gtest/gtest.h>

#include <bot_core/image_t.hpp>
#include <lcm/lcm-cpp.hpp>
#include <rsd/velocity_t.hpp>

#include <map>

#include "tools/sim/sim_lcm_log.hpp"

using namespace rsd;

namespace {

std::string meta(const bot_core::image_t& img, const std::string& key) {
  for (const auto& m : img.metadata)
    if (m.key == key) return std::string(m.value.begin(), m.value.end());
  return "<missing>";
}

}  // namespace

TEST(SimLcmLog, FingerprintMatchesLibbot2) {
  // libbot2's generated bindings publish 0x6fee6cb20472ff6a as bot_core.image_t's base hash;
  // LCM's fingerprint is (base + nested hashes) rotated left by one. A different value would
  // mean existing LCM image viewers could not decode rsd's images.
  const uint64_t libbot2_base = 0x6fee6cb20472ff6aULL;
  uint64_t h = libbot2_base + static_cast<uint64_t>(bot_core::image_metadata_t::getHash());
  h = (h << 1) + ((h >> 63) & 1);
  EXPECT_EQ(static_cast<uint64_t>(bot_core::image_t::getHash()), h);
}

TEST(SimLcmLog, FramesAndVelocityDecode) {
  const std::string path = testing::TempDir() + "/rsd-sim-test.lcmlog";
  dsp::RowTiming timing = dsp::RowTiming::full_frame(48, 30);
  timing.line_delay_s = 1.0 / (48 * 30) * 0.8;
  dsp::Twist tw;
  tw.v = {0.3, -0.2, 0.1};
  tw.w = {0.5, -0.4, 1.2};
  const dsp::ScrewMotion motion(tw);
  const std::vector<double> times = {10.0, 10.0 + 1 / 30.0, 10.0 + 2 / 30.0};
  tools::write_sim_lcm_log({path, timing, 200.0}, times, 64, 48, dsp::PixelFormat::Mono8,
                           [](size_t k, const dsp::ImageView& v) {
                             for (int y = 0; y < v.height; ++y)
                               for (int x = 0; x < v.width; ++x) v.row(y)[x] = static_cast<uint8_t>(x + y + k);
                           },
                           motion);
  lcm::LogFile log(path, "r");
  ASSERT_TRUE(log.good());
  std::map<std::string, int> count;
  int64_t last = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    ++count[ev->channel];
    EXPECT_GE(ev->timestamp, last);  // events in time order
    last = ev->timestamp;
    if (ev->channel == tools::kRawChannel) {
      bot_core::image_t img;
      ASSERT_EQ(img.decode(ev->data, 0, ev->datalen), ev->datalen);
      const int k = count[ev->channel] - 1;
      EXPECT_EQ(img.utime, static_cast<int64_t>(std::llround(times[k] * 1e6)));
      EXPECT_EQ(img.pixelformat, int32_t(bot_core::image_t::PIXEL_FORMAT_GRAY));
      EXPECT_EQ(img.size, 64 * 48);
      EXPECT_EQ(img.data[5 * 64 + 7], 5 + 7 + k);
      EXPECT_NEAR(std::stod(meta(img, "line_delay_ns")), timing.line_delay_s * 1e9, 1e-6);
      EXPECT_EQ(meta(img, "readout"), "top_to_bottom");
      EXPECT_EQ(meta(img, "sequence"), std::to_string(k));
    } else {
      rsd::velocity_t v;
      ASSERT_EQ(v.decode(ev->data, 0, ev->datalen), ev->datalen);
      // With a constant body twist (X_c = exp(t xi^) X) the camera's own rates, in its axes,
      // are the negated twist at every instant.
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(v.angular_velocity[i], -tw.w[i], 1e-6);
      for (int i = 0; i < 3; ++i) EXPECT_NEAR(v.linear_velocity[i], -tw.v[i], 1e-6);
      EXPECT_EQ(int(v.frame), int(rsd::velocity_t::FRAME_CAMERA));
    }
  }
  EXPECT_EQ(count[tools::kRawChannel], 3);
  EXPECT_GE(count[tools::kVelocityChannel], 30);  // 200 Hz from 0.1 s before the first frame
  std::remove(path.c_str());
}
