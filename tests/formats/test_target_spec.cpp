// Calibration targets named as rsd-extract's --target takes them.
#include <gtest/gtest.h>

#include <stdexcept>

#include "formats/target_spec.hpp"

namespace rsd {
namespace {

TEST(TargetSpecText, ParsesBothKindsAndRefusesNonsense) {
  const dsp::TargetSpec c = formats::parse_target("checkerboard:9x7:0.04");
  EXPECT_EQ(c.kind, dsp::TargetKind::Checkerboard);
  EXPECT_EQ(c.cols, 9);
  EXPECT_EQ(c.rows, 7);
  EXPECT_DOUBLE_EQ(c.spacing_m, 0.04);
  const dsp::TargetSpec g = formats::parse_target("aprilgrid:6x5:0.088:0.25");
  EXPECT_EQ(g.kind, dsp::TargetKind::AprilGrid);
  EXPECT_EQ(g.cols, 6);
  EXPECT_EQ(g.rows, 5);
  EXPECT_DOUBLE_EQ(g.tag_spacing, 0.25);
  EXPECT_DOUBLE_EQ(formats::parse_target("aprilgrid:6x6:0.088").tag_spacing, 0.3);  // Kalibr's default
  for (const char* bad : {"checkerboard:9x9:0.04", "checkerboard:9x7", "checkerboard:9x7:-1", "chess:9x7:0.1",
                          "aprilgrid:6:0.088", "aprilgrid:6x6:0.088:0", "checkerboard:9.5x7:0.1", "aprilgrid:30x30:0.01"})
    EXPECT_THROW(formats::parse_target(bad), std::invalid_argument) << bad;
}

}  // namespace
}  // namespace rsd
