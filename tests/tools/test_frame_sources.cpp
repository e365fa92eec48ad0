// Tools read frames from files, LCM logs and live cameras through one interface: an LCM log
// written by the simulator reads back pixel for pixel with its timestamps; bad inputs are
// refused with messages that name them.
#include <gtest/gtest.h>

#include <cstdio>

#include "tools/common/cli_util.hpp"
#include "tools/common/frame_sources.hpp"
#include "tools/sim/sim_lcm_log.hpp"

using namespace rsd;

TEST(FrameSources, LcmLogFramesReadBackExactly) {
  const std::string path = testing::TempDir() + "/rsd-frames.lcmlog";
  const std::vector<double> times = {5.0, 5.1, 5.2, 5.3};
  auto pattern = [](size_t k, const dsp::ImageView& v) {
    for (int y = 0; y < v.height; ++y)
      for (int x = 0; x < v.width; ++x) v.row(y)[x] = static_cast<uint8_t>(3 * x + 5 * y + 7 * k);
  };
  tools::write_sim_lcm_log({path, dsp::RowTiming::full_frame(20, 10), 100.0}, times, 30, 20, dsp::PixelFormat::Mono8,
                           pattern, dsp::ScrewMotion(dsp::Twist{}));
  auto src = tools::open_frame_source({path}, {});
  int k = 0;
  while (auto f = src->next()) {
    ASSERT_EQ(f->image.width, 30);
    ASSERT_EQ(f->image.height, 20);
    EXPECT_NEAR(*f->timestamp_s, times[k], 1e-6);
    EXPECT_EQ(f->image.data[4 * 30 + 9], static_cast<uint8_t>(3 * 9 + 5 * 4 + 7 * k));
    ++k;
  }
  EXPECT_EQ(k, 4);
  try {
    auto wrong = tools::open_frame_source({path}, {"NOT_A_CHANNEL", 1});
    wrong->next();
    FAIL() << "a log without frames on the channel must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no usable raw frame (bot_core.image_t) on channel 'NOT_A_CHANNEL'"), std::string::npos)
        << e.what();
  }
  std::remove(path.c_str());
}

TEST(FrameSources, LiveCameraThatIsNotThereSaysSo) {
  try {
    tools::open_frame_source({"live:v4l2:/dev/video-rsd-test-none"}, {});
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/video-rsd-test-none"), std::string::npos) << e.what();
  }
  EXPECT_THROW(tools::open_frame_source({"live:firewire:0"}, {}), tools::UsageError);
  EXPECT_THROW(tools::open_frame_source({"/nonexistent/rsd/frames"}, {}), tools::UsageError);
}
