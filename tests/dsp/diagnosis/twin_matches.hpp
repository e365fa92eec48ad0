// Twin features, as a tracker's detector makes them: every match of a matches recording gets a
// twin 8 px to its right (inside one 21 px window) whose error correlates `rho` with its own, at
// the same variance. The recording's nominal model must be its truth (its residual is the noise).
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <random>
#include <vector>

#include "dsp/diagnosis/model.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"
#include "dsp/sim/recording_simulation.hpp"

namespace rsd::test {

// Appends the twins after the originals (twin k of match k at index n + k); returns the
// originals' per-coordinate noise.
inline double add_correlated_twins(dsp::SimulatedRecording& sim, double rho, unsigned seed) {
  const size_t n = sim.rec.matches.size();
  for (size_t k = 0; k < n; ++k) {
    dsp::Match twin = sim.rec.matches[k];
    twin.a.x() += 8, twin.b.x() += 8;
    sim.rec.matches.push_back(twin);
  }
  const dsp::DiagnosisModel m(sim.rec);
  const auto r = m.residuals(dsp::nominal_params(sim.rec.nominal), every_observation(m));
  double sum2 = 0;
  for (size_t k = 0; k < n; ++k) sum2 += r[k].squaredNorm();
  const double sigma = std::sqrt(sum2 / (2.0 * n));
  std::mt19937 rng(seed);
  std::normal_distribution<double> fresh(0, sigma);
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d predicted = sim.rec.matches[n + k].b - r[n + k];
    sim.rec.matches[n + k].b =
        predicted + rho * r[k] + std::sqrt(1 - rho * rho) * Eigen::Vector2d(fresh(rng), fresh(rng));
  }
  return sigma;
}

}  // namespace rsd::test
