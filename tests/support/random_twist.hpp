// Random twists for property tests: each component uniform in [-max, max] where its mask is 1.
#pragma once

#include <random>

#include "dsp/geometry/camera_motion.hpp"

namespace rsd::test {

inline dsp::Twist random_twist(std::mt19937& rng, const Eigen::Vector3d& vmask, const Eigen::Vector3d& wmask, double vmax,
                               double wmax) {
  std::uniform_real_distribution<double> a(-1, 1);
  dsp::Twist tw;
  for (int i = 0; i < 3; ++i) {
    tw.v[i] = vmask[i] * vmax * a(rng);
    tw.w[i] = wmask[i] * wmax * a(rng);
  }
  return tw;
}

}  // namespace rsd::test
