// own_depths: each match's own depth in the translation nuisance (dsp/diagnosis/own_depth.hpp),
// against the depth found by brute force, and the bounds that keep a mismatch from taking more
// than a depth's flow, past which the residual moves continuously.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "dsp/diagnosis/own_depth.hpp"

namespace rsd::test {
namespace {

using dsp::own_depths;
using dsp::own_metric;

// The e within [lo, hi] that minimises |left - a e|^2 + (depth_px e)^2 (the data's misfit and
// the prior's, in sigma^2 units times sigma^2), found on a grid and refined by golden sections: a
// search, not the closed form own_depths uses.
double brute_force_depth(const Eigen::Vector2d& a, const Eigen::Vector2d& left, double depth_px, double lo = -10,
                         double hi = 10) {
  auto cost = [&](double e) { return (left - a * e).squaredNorm() + depth_px * depth_px * e * e; };
  double best = lo;
  for (double e = lo; e <= hi; e += 1e-3)
    if (cost(e) < cost(best)) best = e;
  double from = std::max(lo, best - 1e-3), to = std::min(hi, best + 1e-3);
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i < 100; ++i) {
    const double x1 = to - g * (to - from), x2 = from + g * (to - from);
    (cost(x1) < cost(x2) ? to : from) = cost(x1) < cost(x2) ? x2 : x1;
  }
  return (from + to) / 2;
}

// The same within the own depth's bounds.
double bounded_depth(const Eigen::Vector2d& a, const Eigen::Vector2d& left, double depth_px) {
  return brute_force_depth(a, left, depth_px, dsp::kMinOwnDepth, dsp::kMaxOwnDepth);
}

TEST(OwnDepth, TakesOutTheFlowOfTheDepthThatBestExplainsTheMatch) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> e_true(-0.6, 2.0);
  const double depth_px = 1.8;
  std::vector<Eigen::Vector2d> flow, left;
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d a(4 * n(rng), 4 * n(rng));
    flow.push_back(a);
    left.push_back(a * e_true(rng) + Eigen::Vector2d(0.5 * n(rng), 0.5 * n(rng)));  // a depth off the plane's, noise
  }
  const std::vector<Eigen::Vector2d> b = own_depths(flow, left, depth_px);
  ASSERT_EQ(b.size(), flow.size());
  int with_own = 0;
  for (size_t k = 0; k < flow.size(); ++k) {
    // Within the bounds (most of them) and at a bound alike, what the own depth leaves is the
    // residual less the flow of that depth.
    const double e = bounded_depth(flow[k], left[k], depth_px);
    if (e > dsp::kMinOwnDepth + 1e-6 && e < dsp::kMaxOwnDepth - 1e-6) ++with_own;
    const Eigen::Vector2d expected = left[k] - flow[k] * e;
    EXPECT_LT((own_metric(b, k, left[k]) - expected).norm(), 1e-6) << "match " << k;
  }
  EXPECT_GT(with_own, 40);
}

TEST(OwnDepth, AMismatchAlongItsFlowGivesUpNoMoreThanTheFlowOfABound) {
  const double depth_px = 1.8;
  const Eigen::Vector2d a(5, 0);
  // A random point 300 px along the match's flow asks for e = 1500 / 28.2 = 53 (a point 54 times
  // nearer than the plane) and gets 3 (four times nearer): 15 of its 300 px go; one 60 px against
  // it asks for e = -10.6 and gets -3, as far the other way; a near point asks for e = 2 (three
  // times nearer) and gets it.
  const std::vector<Eigen::Vector2d> left = {{300, 2}, {-60, 1}, {10, 0.3}};
  const std::vector<Eigen::Vector2d> b = own_depths({a, a, a}, left, depth_px);
  const double asks[3] = {1500 / (25 + depth_px * depth_px), -300 / (25 + depth_px * depth_px),
                          50 / (25 + depth_px * depth_px)};
  const double gets[3] = {dsp::kMaxOwnDepth, dsp::kMinOwnDepth, asks[2]};
  for (size_t k = 0; k < left.size(); ++k) {
    EXPECT_NEAR(brute_force_depth(a, left[k], depth_px, -100, 100), asks[k], 1e-6) << "match " << k;
    const double e = bounded_depth(a, left[k], depth_px);
    EXPECT_NEAR(e, gets[k], 1e-6) << "match " << k;
    EXPECT_LT((own_metric(b, k, left[k]) - (left[k] - a * e)).norm(), 1e-6) << "match " << k;
  }
  // A failed prediction's residual (not finite) gets no own depth.
  const Eigen::Vector2d failed = Eigen::Vector2d::Constant(std::nan(""));
  EXPECT_EQ(own_depths({a}, {failed}, depth_px)[0], Eigen::Vector2d::Zero());
  // Without own depths (one plane) nothing is taken out.
  EXPECT_TRUE(own_depths({a}, {left[2]}, 0.0).empty());
  EXPECT_EQ(own_metric({}, 0, left[2]), left[2]);
}

// Past its bounds an own depth stays at the bound: the match gives up the flow of the bound's
// depth, so that the residual moves continuously as a parameter moves e across a bound (the
// fade of the sixtieth session dropped the own depth of a match whose noise carried its e past a
// bound). Against the bounded brute force, every 0.01 of e from -5 to 5.
TEST(OwnDepth, PastItsBoundsAnOwnDepthStaysAtTheBound) {
  const double depth_px = 1.8;
  const Eigen::Vector2d a(5, 0), across(0, 0.7);
  const double q = a.squaredNorm() + depth_px * depth_px;
  Eigen::Vector2d last = Eigen::Vector2d::Constant(std::nan(""));
  double largest_step = 0;
  for (int step = -500; step <= 500; ++step) {
    const double e = step / 100.0;
    const Eigen::Vector2d left = a * (e * q / a.squaredNorm()) + across;  // asks for own depth e
    const std::vector<Eigen::Vector2d> b = own_depths({a}, {left}, depth_px);
    const Eigen::Vector2d r = own_metric(b, 0, left);
    if (step % 10 == 0) {
      const double got = bounded_depth(a, left, depth_px);
      EXPECT_NEAR(got, std::clamp(e, dsp::kMinOwnDepth, dsp::kMaxOwnDepth), 1e-6) << "e " << e;
      EXPECT_LT((r - (left - a * got)).norm(), 1e-6) << "e " << e;
    }
    if (last.allFinite()) largest_step = std::max(largest_step, (r - last).norm());
    last = r;
  }
  // A step of 0.01 in e moves the residual by 0.01 depth_px^2 / |a| (0.0065 px) where the depth
  // follows it, by 0.01 q / |a| (0.056 px) where it stays at a bound: no jump at the bounds (switched
  // off at e = 3, 3 q / |a| = 17 px at once; faded, 0.01 |a| (q / |a|^2 + 4) = 0.26 px).
  EXPECT_LT(largest_step, 0.01 * q / a.norm() + 1e-9);
  EXPECT_GT(largest_step, 0.99 * 0.01 * q / a.norm());
}

// A match on the plane whose flow is about the noise asks for an own depth of about one either
// way: what the own depths leave along the flow must average zero, or it points towards the focus
// of expansion or away from it, and the velocity and the clock offset follow. Cut at -1 (a point
// at infinity) and 3, the mean left along a flow of one noise was -0.046 noises over 20 000
// matches (21 standard errors): the independent drone at 60 fps named its clock offset 2.4 to
// 11.1 ms early.
TEST(OwnDepth, WhatItLeavesAlongTheFlowAveragesZeroWhereTheFlowIsTheNoise) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double depth_px = 0.45;  // a prior four times the drone's measured spread, 0.55
  const int n = 20000;
  const std::vector<Eigen::Vector2d> flow(n, Eigen::Vector2d(1.0, 0.0));
  std::vector<Eigen::Vector2d> left(n);
  for (Eigen::Vector2d& l : left) l = Eigen::Vector2d(noise(rng), noise(rng));
  const std::vector<Eigen::Vector2d> b = own_depths(flow, left, depth_px);
  double sum = 0, sum2 = 0;
  for (int k = 0; k < n; ++k) {
    const double along = own_metric(b, static_cast<size_t>(k), left[k]).x();
    sum += along, sum2 += along * along;
  }
  const double mean = sum / n, se = std::sqrt((sum2 / n - mean * mean) / n);
  EXPECT_LT(std::abs(mean), 5 * se) << "mean " << mean << " standard error " << se;
  EXPECT_LT(se, 0.002);
}

}  // namespace
}  // namespace rsd::test
