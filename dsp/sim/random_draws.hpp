// Vectors of random draws in a fixed order, so that a scenario's seed gives the same recording
// whichever compiler built the simulator.
//
// Why: the arguments of one call are evaluated in an unspecified order, so a vector built as
// Vector3d(n(rng), n(rng), n(rng)) takes its draws right to left under gcc and left to right
// under clang, and the same seed gave two recordings (found when the ASan tree moved to clang).
// The draws here go last component first, the order gcc's builds always used, so that every
// recording made before keeps its numbers.
#pragma once

#include <Eigen/Core>
#include <random>

namespace rsd::dsp {

// N draws of one distribution: component N-1 first, component 0 last.
template <int N, class Dist>
Eigen::Matrix<double, N, 1> draw(Dist& dist, std::mt19937& rng) {
  Eigen::Matrix<double, N, 1> v;
  for (int i = N - 1; i >= 0; --i) v[i] = dist(rng);
  return v;
}

// A point (x from dx, y from dy): y first, then x.
template <class DistX, class DistY>
Eigen::Vector2d draw(DistX& dx, DistY& dy, std::mt19937& rng) {
  const double y = dy(rng);
  const double x = dx(rng);
  return {x, y};
}

}  // namespace rsd::dsp
