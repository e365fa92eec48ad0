// dsp/diagnosis/plausibility: the soft bounds of what real hardware has, against their stated
// arithmetic (a penalty of the squared widths past the bound; past two widths never named).
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "dsp/diagnosis/effects.hpp"
#include "dsp/diagnosis/plausibility.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"

using namespace rsd::dsp;

namespace {

ModelParams with_drift(const NominalModel& n, double ppm) {
  ModelParams p = nominal_params(n);
  p[Param::Drift] = ppm;
  return p;
}

}  // namespace

// A clock drift within 1000 ppm costs nothing; each 250 ppm past it one sigma squared; past two
// widths (1500 ppm) it is beyond any camera's and IMU's clocks and never named. 3755 ppm is what
// stood in for the Karma clip's moved clock (docs/diagnosis.md, "Real recordings").
TEST(Plausibility, AClockDriftPastAThousandPpmCostsAndPastFifteenHundredIsNeverNamed) {
  const SimulatedRecording sim = simulate_recording(rsd::test::simulation(ObservationKind::Matches, 5, 1.0, 0.5));
  const DiagnosisModel m(sim.rec);
  const NominalModel& n = sim.rec.nominal;
  for (double ppm : {0.0, 300.0, -999.0}) {
    EXPECT_EQ(implausibility(with_drift(n, ppm), {Effect::ClockDrift}), 0.0) << ppm;
    EXPECT_EQ(implausible_because(with_drift(n, ppm), Effect::ClockDrift), "") << ppm;
  }
  EXPECT_NEAR(implausibility(with_drift(n, 1250), {Effect::ClockDrift}), 1.0, 1e-12);
  EXPECT_NEAR(implausibility(with_drift(n, -1500), {Effect::ClockDrift}), 4.0, 1e-12);
  EXPECT_EQ(beyond_hardware_because(with_drift(n, 1400), Effect::ClockDrift, m), "");
  const std::string why = beyond_hardware_because(with_drift(n, -3755), Effect::ClockDrift, m);
  EXPECT_NE(why.find("clock drift of -3755 ppm"), std::string::npos) << why;
  // Another effect's penalty does not count a drift it does not name.
  EXPECT_EQ(implausibility(with_drift(n, -3755), {Effect::TimeOffset}), 0.0);
}

// A focal length within 25% of the nominal may be named; past it, never, and the reason says the
// value, the nominal and what to do when the nominal is the guess (the Karma clip's guessed
// 400 px lens wanted 621 px).
TEST(Plausibility, AFocalLengthPastAQuarterOfTheNominalIsNeverNamedAndTheNominalIsQuestioned) {
  const SimulatedRecording sim = simulate_recording(rsd::test::simulation(ObservationKind::Matches, 5, 1.0, 0.5));
  const DiagnosisModel m(sim.rec);
  const NominalModel& n = sim.rec.nominal;
  auto with_focal = [&](double scale) {
    ModelParams p = nominal_params(n);
    p[Param::Fx] = scale * n.cam.fx, p[Param::Fy] = scale * n.cam.fy;
    return p;
  };
  EXPECT_EQ(beyond_hardware_because(with_focal(1.24), Effect::FocalLength, m), "");
  EXPECT_EQ(beyond_hardware_because(with_focal(0.76), Effect::FocalLength, m), "");
  const std::string why = beyond_hardware_because(with_focal(1.552), Effect::FocalLength, m);
  std::ostringstream expected;
  expected.precision(3);
  expected << "a focal length of " << 1.552 * n.cam.fx << " px, 55.2% from the nominal " << n.cam.fx << " px";
  EXPECT_EQ(why.rfind(expected.str(), 0), 0u) << why;
  EXPECT_NE(why.find("rsd-calib import-lens"), std::string::npos) << why;
}
