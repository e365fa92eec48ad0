// Matches made from pictures (tools/common/picture_observations): the frame pairs tracked when a
// recording has more than the budget, against pictures whose motion is known (crops of one
// texture moved 3 px right per frame, so every match's second end lies 3 px left of its first).
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <set>

#include "tools/common/picture_observations.hpp"

using namespace rsd;

namespace {

constexpr int kFrames = 10, kW = 160, kH = 120, kStepPx = 3;

// Smoothed noise: corners everywhere, trackable to a small fraction of a pixel.
cv::Mat texture() {
  cv::Mat t(kH + 20, kW + kStepPx * kFrames + 20, CV_8UC1);
  cv::RNG rng(7);
  rng.fill(t, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(t, t, cv::Size(0, 0), 2.0);
  cv::normalize(t, t, 0, 255, cv::NORM_MINMAX);
  return t;
}

struct Frames {
  cv::Mat tex = texture();
  int read = 0;
  tools::PictureFrames f;
  dsp::Recording rec;
  Frames() {
    f.what = "test pictures";
    f.next = [this]() -> std::optional<dsp::Image> {
      if (read == kFrames) return std::nullopt;
      dsp::Image img(kW, kH, dsp::PixelFormat::Mono8);
      tex(cv::Rect(10 + kStepPx * read, 10, kW, kH)).copyTo(cv::Mat(kH, kW, CV_8UC1, img.data.data()));
      ++read;
      return img;
    };
    rec.kind = dsp::ObservationKind::Matches;
    rec.motion = dsp::MotionKind::Gyro;
    for (int k = 0; k < kFrames; ++k) {
      f.numbers.push_back(100 + k), f.times.push_back(k / 30.0), f.usable.push_back(true);
      rec.frames.push_back({100 + k, k / 30.0});
    }
    for (double t = -0.5; t < 1.0; t += 0.005) rec.gyro.push_back({t, Eigen::Vector3d(0, 0.1, 0)});
  }
};

// Frame pairs with matches, and the median error of a match's displacement from the truth.
std::set<std::pair<int, int>> pairs_of(const dsp::Recording& rec, double& median_px) {
  std::set<std::pair<int, int>> p;
  std::vector<double> e;
  for (const dsp::Match& m : rec.matches) {
    p.insert({m.frame_a, m.frame_b});
    e.push_back((m.b - m.a - Eigen::Vector2d(-kStepPx, 0)).norm());
  }
  std::nth_element(e.begin(), e.begin() + e.size() / 2, e.end());
  median_px = e.empty() ? 1e9 : e[e.size() / 2];
  return p;
}

}  // namespace

TEST(MakeMatches, TracksEveryPairOfUsableFramesWithinTheBudget) {
  Frames s;
  s.f.usable[4] = false;  // its pairs (103, 104) and (104, 105) are not tracked
  tools::make_matches(s.f, dsp::TrackOptions{}, s.rec, 0);
  double median = 0;  // px
  const std::set<std::pair<int, int>> p = pairs_of(s.rec, median);
  EXPECT_EQ(p.size(), 7u);
  EXPECT_FALSE(p.count({103, 104}));
  EXPECT_FALSE(p.count({104, 105}));
  EXPECT_LT(median, 0.02);
  EXPECT_EQ(s.read, kFrames);
  EXPECT_EQ(s.rec.frames.size(), 9u);  // every frame but 104 belongs to a tracked pair
}

TEST(MakeMatches, TracksOnlyTheChosenPairsAndKeepsTheirFrames) {
  Frames s;
  tools::make_matches(s.f, dsp::TrackOptions{}, s.rec, 3);
  double median = 0;  // px
  const std::set<std::pair<int, int>> p = pairs_of(s.rec, median);
  ASSERT_EQ(p.size(), 3u);
  std::set<int> frames;
  for (const auto& [a, b] : p) {
    EXPECT_EQ(b, a + 1) << "a pair of consecutive frames";
    frames.insert(a), frames.insert(b);
  }
  EXPECT_LT(median, 0.02);  // a pair tracked alone matches as well as within a chain
  EXPECT_EQ(s.read, kFrames);  // every picture read, in order, the skipped ones too
  ASSERT_EQ(s.rec.frames.size(), frames.size());
  for (const dsp::FrameStamp& f : s.rec.frames) EXPECT_TRUE(frames.count(f.frame)) << f.frame;
}

TEST(MakeMatches, SaysWhichFrameCouldNotBeRead) {
  Frames s;
  s.f.numbers.push_back(110), s.f.times.push_back(10 / 30.0), s.f.usable.push_back(true);  // one more than the source has
  try {
    tools::make_matches(s.f, dsp::TrackOptions{}, s.rec, 3);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("test pictures: frame 110 could not be read"), std::string::npos) << e.what();
  }
}
