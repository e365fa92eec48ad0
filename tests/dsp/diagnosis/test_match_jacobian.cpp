// The analytic Jacobian of a match's residual (match_jacobian.hpp, DiagnosisModel::
// rotation_jacobian) against central differences of DiagnosisModel::residual, the model's own
// residual with its fixed point solved anew: every parameter with an analytic column, for
// either lens family as the nominal one and as the other (lens_model), with a mount rotation,
// a clock drift, a gyro bias and scale and either readout direction away from the nominal. The
// gyro's columns integrate the change of rate by Simpson's rule where the residual
// re-integrates the track.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "dsp/diagnosis/match_jacobian.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"

using namespace rsd::dsp;

namespace {

struct Variant {
  const char* name;
  LensModel nominal_lens;
  bool other_lens, flip_readout;
  bool phone_gyro = false;  // sampled at 20-200 Hz with gaps, jitter and noise (a phone's)
};

SimulatedRecording recording(LensModel lens, bool phone_gyro) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, 5, 1.0, 0.3);
  c.start_time_s = 1000;
  c.matches_per_pair = 20;
  c.rotation_amplitude_rad = 0.3, c.motion_frequency_hz = 1.5;
  c.effects.line_delay_s = 5e-5;
  c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;  // a phone's gyro axes: E other than I
  if (phone_gyro) c.gyro = {20, 200, 0.02, 0.03, 5e-4, 0.002};
  if (lens == LensModel::PinholeEqui) c.nominal.cam.dist = Distortion::equidistant(0.02, -0.01, 0.003, -0.001);
  else c.nominal.cam.dist = Distortion{-0.08, 0.02, 1e-3, -5e-4};  // k1, k2, p1, p2: tangential terms too
  return simulate_recording(c);
}

// A point away from the nominal in every analytic parameter.
ModelParams away(const NominalModel& n, const Variant& v) {
  ModelParams p = nominal_params(n);
  p.other_lens = v.other_lens, p.flip_readout = v.flip_readout;
  p[Param::LineDelay] = 4e-5, p[Param::TimeOffset] = 2e-3, p[Param::Drift] = 80;
  p[Param::Fx] *= 1.01, p[Param::Fy] *= 1.005, p[Param::Cx] += 3, p[Param::Cy] -= 2;
  p[Param::K1] += 0.01, p[Param::K2] -= 0.005, p[Param::K3] += 0.002, p[Param::K4] -= 0.001;
  p[Param::MountX] = 0.01, p[Param::MountY] = -0.02, p[Param::MountZ] = 0.005;
  p[Param::BiasX] = 0.002, p[Param::BiasZ] = -0.003;  // a track other than the nominal one
  p[Param::ScaleX] = 1.01, p[Param::ScaleY] = 0.995;
  return p;
}

}  // namespace

class MatchJacobianTest : public testing::TestWithParam<Variant> {};

TEST_P(MatchJacobianTest, EveryColumnAgreesWithCentralDifferencesOfTheResidual) {
  const Variant v = GetParam();
  const SimulatedRecording sim = recording(v.nominal_lens, v.phone_gyro);
  const DiagnosisModel m(sim.rec);
  const NominalModel& n = sim.rec.nominal;
  const ModelParams p = away(n, v);
  std::vector<int> idx;
  for (int i = 0; i < m.size(); i += 7) idx.push_back(i);
  DiagnosisModel::Settled settled;
  const std::vector<Eigen::Vector2d> r = m.residuals(p, idx, settled);
  const std::vector<MatchJacobian> D = m.rotation_jacobian(p, idx, settled);
  ASSERT_EQ(D.size(), idx.size());
  int compared = 0;
  for (size_t c = 0; c < kAnalyticParams.size(); ++c) {
    const Param q = kAnalyticParams[c];
    const double h = 0.01 * param_scale(q, n);
    double worst = 0, largest = 0;
    for (size_t k = 0; k < idx.size(); ++k) {
      if (!r[k].allFinite()) continue;
      ModelParams hi = p, lo = p;
      hi[q] += h, lo[q] -= h;
      const auto rh = m.residual(hi, idx[k]), rl = m.residual(lo, idx[k]);
      if (!rh || !rl) continue;
      const Eigen::Vector2d fd = (*rh - *rl) / (2 * h);
      worst = std::max(worst, (D[k].col(c) - fd).norm() * param_scale(q, n));
      largest = std::max(largest, fd.norm() * param_scale(q, n));
      ++compared;
    }
    std::printf("%-14s largest %.3g px per scale, worst difference %.3g\n", param_name(q), largest, worst);
    // Agreement to 1e-6 of the column's largest here; a radtan lens's K3 and K4 columns are zero
    // both ways (lens_of does not read them).
    EXPECT_LE(worst, 1e-4 * largest + 1e-7) << param_name(q);
  }
  EXPECT_GT(compared, 1000);
}

INSTANTIATE_TEST_SUITE_P(
    Lenses, MatchJacobianTest,
    testing::Values(Variant{"radtan", LensModel::PinholeRadtan, false, false},
                    Variant{"equi", LensModel::PinholeEqui, false, false},
                    Variant{"radtan_as_equi_flipped", LensModel::PinholeRadtan, true, true},
                    Variant{"equi_as_radtan", LensModel::PinholeEqui, true, false},
                    Variant{"radtan_phone_gyro", LensModel::PinholeRadtan, false, false, true}),
    [](const testing::TestParamInfo<Variant>& i) { return std::string(i.param.name); });

// Only the lever arm (the landmarks') has no analytic column.
TEST(MatchJacobian, OnlyTheLeverArmHasNoAnalyticColumn) {
  for (Param q : {Param::LeverX, Param::LeverY, Param::LeverZ}) EXPECT_EQ(analytic_column(q), -1) << param_name(q);
  EXPECT_EQ(kAnalyticParams.size() + 3, static_cast<size_t>(kParamCount));
  for (size_t c = 0; c < kAnalyticParams.size(); ++c) EXPECT_EQ(analytic_column(kAnalyticParams[c]), static_cast<int>(c));
}
