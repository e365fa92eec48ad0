#include <gtest/gtest.h>

#include "dsp/geometry/row_timing.hpp"

using namespace rsd::dsp;

TEST(RowTiming, PaperIdealLineDelays) {
  // The paper's calibration table: about 240 rows read per frame at 3.75, 7.5 and 15 fps
  // give 0.00110, 0.00056 and 0.00028 s per row when d = 0.
  EXPECT_NEAR(RowTiming::full_frame(240, 3.75).line_delay_s, 0.00110, 0.00002);
  EXPECT_NEAR(RowTiming::full_frame(240, 7.5).line_delay_s, 0.00056, 0.00001);
  EXPECT_NEAR(RowTiming::full_frame(240, 15).line_delay_s, 0.00028, 0.000005);
  EXPECT_NEAR(RowTiming::full_frame(240, 15).inter_frame_delay_s(), 0.0, 1e-15);
}

TEST(RowTiming, ConversionsRoundTrip) {
  EXPECT_DOUBLE_EQ(row_rate_from_line_delay(1e-5), 1e5);
  EXPECT_DOUBLE_EQ(line_delay_from_row_rate(-1e5), 1e-5);
  EXPECT_DOUBLE_EQ(frame_readout_from_line_delay(2e-5, 1080), 0.0216);
  EXPECT_DOUBLE_EQ(line_delay_from_frame_readout(0.0216, 1080), 2e-5);
}

TEST(RowTiming, TopToBottomMatchesRecordingSpec) {
  // recording-v1: t = T_k + line_delay * v.
  RowTiming t;
  t.height = 1080;
  t.line_delay_s = 1.9e-5;
  EXPECT_DOUBLE_EQ(t.r(), 1 / 1.9e-5);
  EXPECT_DOUBLE_EQ(t.v0(), 0);
  EXPECT_NEAR(t.row_time(500), 500 * 1.9e-5, 1e-15);
  EXPECT_NEAR(t.row_at(t.row_time(123.25)), 123.25, 1e-9);
}

TEST(RowTiming, BottomToTopMatchesRecordingSpec) {
  // recording-v1: t = T_k + line_delay * (height - 1 - v); the paper's r is negative.
  RowTiming t;
  t.height = 1080;
  t.line_delay_s = 1.9e-5;
  t.readout = Readout::BottomToTop;
  EXPECT_LT(t.r(), 0);
  EXPECT_DOUBLE_EQ(t.v0(), -1079);
  EXPECT_NEAR(t.row_time(1079), 0, 1e-15);
  EXPECT_NEAR(t.row_time(500), (1079 - 500) * 1.9e-5, 1e-15);
  EXPECT_NEAR(t.row_at(t.row_time(7.5)), 7.5, 1e-9);
}

TEST(RowTiming, BlankingAndExposureMidpoint) {
  RowTiming t = RowTiming::full_frame(480, 30);
  t.line_delay_s = 0.025 / 480;  // 25 ms readout in a 33.3 ms frame
  EXPECT_NEAR(t.frame_readout_s(), 0.025, 1e-15);
  EXPECT_NEAR(t.inter_frame_delay_s(), 1.0 / 30 - 0.025, 1e-15);
  t.exposure_s = 0.004;
  EXPECT_NEAR(t.row_mid_exposure(100), t.row_time(100) + 0.002, 1e-15);
}

TEST(RowTiming, FirstRowOverridesNaturalStart) {
  RowTiming t;
  t.first_row = 16;  // e.g. a cropped sensor that starts reading at row 16
  EXPECT_NEAR(t.row_time(16), 0, 1e-15);
  EXPECT_NEAR(t.row_at(0), 16, 1e-12);
}

TEST(RowTiming, ParsesReadoutNames) {
  Readout r;
  EXPECT_TRUE(parse_readout("bottom_to_top", r));
  EXPECT_EQ(r, Readout::BottomToTop);
  EXPECT_TRUE(parse_readout("top_to_bottom", r));
  EXPECT_EQ(r, Readout::TopToBottom);
  EXPECT_FALSE(parse_readout("sideways", r));
  EXPECT_EQ(to_string(Readout::BottomToTop), "bottom_to_top");
}
