// own_depths: each match's own depth in the translation nuisance (dsp/diagnosis/own_depth.hpp),
// against the depth found by brute force, the bound that keeps a mismatch from taking one, and
// the fade past it that keeps the residual continuous.
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

// The e that minimises |left - a e|^2 + (depth_px e)^2 (the data's misfit and the prior's, in
// sigma^2 units times sigma^2), found on a grid and refined by golden sections: a search, not
// the closed form own_depths uses.
double brute_force_depth(const Eigen::Vector2d& a, const Eigen::Vector2d& left, double depth_px) {
  auto cost = [&](double e) { return (left - a * e).squaredNorm() + depth_px * depth_px * e * e; };
  double best = 0;
  for (double e = -10; e <= 10; e += 1e-3)
    if (cost(e) < cost(best)) best = e;
  double lo = best - 1e-3, hi = best + 1e-3;
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i < 100; ++i) {
    const double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    (cost(x1) < cost(x2) ? hi : lo) = cost(x1) < cost(x2) ? x2 : x1;
  }
  return (lo + hi) / 2;
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
    const double e = brute_force_depth(flow[k], left[k], depth_px);
    if (e < dsp::kMinOwnDepth || e > dsp::kMaxOwnDepth) continue;
    ++with_own;
    // What the own depth leaves is the residual less the flow of that depth.
    const Eigen::Vector2d expected = left[k] - flow[k] * e;
    EXPECT_LT((own_metric(b, k, left[k]) - expected).norm(), 1e-6) << "match " << k;
  }
  EXPECT_GT(with_own, 40);
}

TEST(OwnDepth, AMismatchAlongItsFlowKeepsItsWholeResidual) {
  const double depth_px = 1.8;
  const Eigen::Vector2d a(5, 0);
  // A random point 300 px along the match's flow asks for e = 1500 / 28.2 = 53 (a point 54 times
  // nearer than the plane); one 60 px against it for e = -10.6 (beyond infinity); a near point
  // for e = 2 (three times nearer), which it gets.
  const std::vector<Eigen::Vector2d> left = {{300, 2}, {-60, 1}, {10, 0.3}};
  const std::vector<Eigen::Vector2d> b = own_depths({a, a, a}, left, depth_px);
  EXPECT_EQ(own_metric(b, 0, left[0]), left[0]);
  EXPECT_EQ(own_metric(b, 1, left[1]), left[1]);
  const double e = brute_force_depth(a, left[2], depth_px);
  EXPECT_NEAR(e, 10.0 * 5 / (25 + depth_px * depth_px), 1e-6);
  EXPECT_LT((own_metric(b, 2, left[2]) - (left[2] - a * e)).norm(), 1e-6);
  // Without own depths (one plane) nothing is taken out.
  EXPECT_TRUE(own_depths({a}, {left[2]}, 0.0).empty());
  EXPECT_EQ(own_metric({}, 0, left[2]), left[2]);
}

// Past its bounds an own depth fades out: what the match's residual keeps of the flow of its
// depth goes linearly from none to all over kOwnDepthFade beyond kMaxOwnDepth (half of it below
// kMinOwnDepth), so that the residual moves continuously as a parameter moves e across a bound.
// Against the residual less kept(e) a e, kept the straight line between the band's ends; the
// residuals are made to ask for e, which brute force confirms every 0.5.
TEST(OwnDepth, PastItsBoundsAnOwnDepthFadesOutContinuously) {
  const double depth_px = 1.8;
  const Eigen::Vector2d a(5, 0), across(0, 0.7);
  const double q = a.squaredNorm() + depth_px * depth_px;
  auto kept_by_hand = [](double e) {
    if (e <= -1.5 || e >= 4.0) return 0.0;
    if (e < -1.0) return (e + 1.5) / 0.5;
    return e > 3.0 ? 4.0 - e : 1.0;
  };
  Eigen::Vector2d last = Eigen::Vector2d::Constant(std::nan(""));
  double largest_step = 0;
  for (int step = -250; step <= 500; ++step) {
    const double e = step / 100.0;
    const Eigen::Vector2d left = a * (e * q / a.squaredNorm()) + across;  // asks for own depth e
    const std::vector<Eigen::Vector2d> b = own_depths({a}, {left}, depth_px);
    if (step % 50 == 0) {
      ASSERT_NEAR(brute_force_depth(a, left, depth_px), e, 1e-6);
    }
    const Eigen::Vector2d r = own_metric(b, 0, left);
    EXPECT_LT((r - (left - kept_by_hand(e) * a * e)).norm(), 1e-6) << "e " << e;
    EXPECT_NEAR(dsp::own_depth_kept(e), kept_by_hand(e), 1e-12) << "e " << e;
    if (last.allFinite()) largest_step = std::max(largest_step, (r - last).norm());
    last = r;
  }
  // A step of 0.01 in e moves the residual by 0.01 depth_px^2 / |a| (0.0065 px) where the depth
  // is taken whole, by 0.01 q / |a| (0.056 px) where none is, and by at most 0.01 |a| (q / |a|^2
  // + 4) (0.26 px) on the upper fade: no jump (switched at e = 3: 3 q / |a| = 17 px at once).
  EXPECT_LT(largest_step, 0.01 * a.norm() * (q / a.squaredNorm() + 4) + 1e-9);
  EXPECT_GT(largest_step, 0.01 * q / a.norm());
}

}  // namespace
}  // namespace rsd::test
