// The tools' progress line (tools/common/progress_line): the bar's length and fill by count, the
// time left said once two steps set the pace and not after the last, the line ended when the
// stage is done and before a message of its own.
#include <gtest/gtest.h>

#include <string>

#include "tools/common/progress_line.hpp"

namespace rsd::tools {
namespace {

TEST(ProgressLine, TheBarIsFilledByTheShareDone) {
  EXPECT_EQ(progress_bar(0, 9), "[--------------------]");
  EXPECT_EQ(progress_bar(3, 9), "[######--------------]");  // 3 x 20 / 9 = 6.7: whole characters only
  EXPECT_EQ(progress_bar(9, 9), "[####################]");
  EXPECT_EQ(progress_bar(12, 9, 4), "[####]");  // never beyond its width
  EXPECT_EQ(progress_bar(1, 0, 4), "[----]");   // no steps: nothing to fill
}

TEST(ProgressLine, SaysTheTimeLeftOnceThePaceIsKnownAndEndsTheLine) {
  testing::internal::CaptureStderr();
  {
    ProgressLine line("tool: ");
    line.step("screening", 1, 3);
    line.step("screening", 2, 3);
    line.step("screening", 3, 3);
    line.step("frames", 1, 4, "12 matches");
    line.message("a stage of its own");
  }
  const std::string out = testing::internal::GetCapturedStderr();
  const size_t first = out.find("1/3"), second = out.find("2/3"), third = out.find("3/3");
  ASSERT_NE(first, std::string::npos);
  ASSERT_NE(second, std::string::npos);
  ASSERT_NE(third, std::string::npos);
  EXPECT_EQ(out.substr(first, second - first).find("s left"), std::string::npos) << out;  // one step: no pace yet
  EXPECT_NE(out.substr(second, third - second).find("s left"), std::string::npos) << out;
  EXPECT_EQ(out.substr(third, out.find('\n', third) - third).find("s left"), std::string::npos) << out;
  EXPECT_NE(out.find("1/4, 12 matches"), std::string::npos) << out;
  // The unfinished line is ended before the message, which has a line of its own.
  EXPECT_NE(out.find("\ntool: a stage of its own\n"), std::string::npos) << out;
}

}  // namespace
}  // namespace rsd::tools
