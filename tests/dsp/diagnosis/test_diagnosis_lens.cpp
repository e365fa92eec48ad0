// The diagnosis's lens effects (spec "Named effects", "Lens models") on simulated matches
// recordings through wide-angle lenses, each judged on held-out frames: a fisheye hidden behind
// the pinhole-radtan lens nearest to it (what a pinhole calibration of a fisheye gives) is named
// lens_model pinhole-equi with its terms; the reverse, a pinhole camera behind an equidistant
// nominal, is named lens_model pinhole-radtan; an equidistant nominal whose k3, k4 are wrong is
// named lens_distortion with k1..k4. Ground truth: the simulator's lens, and the spec's
// equations in an independent form (the Taylor series of tan and atan) for nearest_lens.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/geometry/lens_model.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/dsp/diagnosis/diagnosis_lookup.hpp"
#include "tests/support/sanitizer.hpp"

using namespace rsd::dsp;
using rsd::test::find;
using rsd::test::names;
using rsd::test::param;

namespace test_diagnosis_lens {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

constexpr double kNoise = 0.5;

// A VGA camera with a wide lens: f = 400 px puts the corners 1 rad (57 degrees) off the axis
// through an equidistant lens.
SimConfig wide(unsigned seed) {
  SimConfig c = rsd::test::simulation(ObservationKind::Matches, seed, 4.0, kNoise);
  c.start_time_s = 1000;
  c.matches_per_pair = 80;
  c.nominal.cam.fx = c.nominal.cam.fy = 400;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  return c;
}

double corner_angle(const CameraModel& cam) { return std::atan(std::hypot(cam.cx, cam.cy) / cam.fx); }

Diagnosis run(const SimConfig& c) {
  const Diagnosis d = diagnose(simulate_recording(c).rec);
  for (const auto& e : d.effects) {
    std::printf("  %s:", e.name.c_str());
    for (const auto& p : e.params) std::printf(" %s=%s", p.name.c_str(), p.text.empty() ? std::to_string(p.value).c_str() : p.text.c_str());
    std::printf("\n");
  }
  std::printf("named [%s] held out %.3f -> %.3f px (floor %.3f)\n", names(d).c_str(), d.heldout_baseline_rms_px,
              d.heldout_final_rms_px, d.noise_floor_px);
  EXPECT_LT(d.heldout_final_rms_px, 1.1 * d.noise_floor_px);
  EXPECT_LT(d.heldout_final_rms_px, d.heldout_baseline_rms_px);
  return d;
}

// The largest difference, in pixels at focal length f, between two lenses' distorted radii over
// the angles 0..max_theta off the axis: the terms of a degree-9 polynomial trade off against
// each other, the picture they make does not.
double lens_difference_px(const Distortion& a, const Distortion& b, double f, double max_theta) {
  double worst = 0;
  for (int i = 1; i <= 200; ++i) {
    const double r = std::tan(max_theta * i / 200);
    worst = std::max(worst, f * (distort(a, {r, 0}) - distort(b, {r, 0})).norm());
  }
  return worst;
}

// The lens a named lens effect describes.
Distortion named_lens(const NamedEffect* e, LensModel family) {
  if (family == LensModel::PinholeEqui)
    return Distortion::equidistant(param(e, "k1"), param(e, "k2"), param(e, "k3"), param(e, "k4"));
  return {param(e, "k1"), param(e, "k2")};
}

std::string text_param(const NamedEffect* e, const std::string& name) {
  if (!e) return "";
  for (const EffectParam& p : e->params)
    if (p.name == name) return p.text;
  return "";
}

}  // namespace

TEST(NearestLens, ASameFamilyLensIsItself) {
  const Distortion equi = Distortion::equidistant(0.03, -0.02, 0.004, -0.001);
  const Distortion e = nearest_lens(equi, LensModel::PinholeEqui, 1.2);
  EXPECT_NEAR(e.k1, equi.k1, 1e-9);
  EXPECT_NEAR(e.k2, equi.k2, 1e-9);
  EXPECT_NEAR(e.k3, equi.k3, 1e-9);
  EXPECT_NEAR(e.k4, equi.k4, 1e-9);
  const Distortion r = nearest_lens({-0.2, 0.05}, LensModel::PinholeRadtan, 0.8);
  EXPECT_EQ(r.model, LensModel::PinholeRadtan);
  EXPECT_NEAR(r.k1, -0.2, 1e-9);
  EXPECT_NEAR(r.k2, 0.05, 1e-9);
}

TEST(NearestLens, AcrossFamiliesNearTheAxisItIsTheTaylorSeries) {
  // A pinhole (tan theta) as an equidistant lens: tan t = t (1 + t^2/3 + 2 t^4/15 + 17 t^6/315 + ...).
  const Distortion e = nearest_lens({}, LensModel::PinholeEqui, 0.2);
  EXPECT_NEAR(e.k1, 1.0 / 3, 1e-4);
  EXPECT_NEAR(e.k2, 2.0 / 15, 2e-3);
  // The equidistant lens as a pinhole: atan r = r (1 - r^2/3 + r^4/5 - ...).
  const Distortion r = nearest_lens(Distortion::equidistant(0, 0, 0, 0), LensModel::PinholeRadtan, 0.15);
  EXPECT_NEAR(r.k1, -1.0 / 3, 1e-3);
  EXPECT_NEAR(r.k2, 1.0 / 5, 2e-2);
}

TEST(DiagnosisLens, AFisheyeBehindAPinholeNominalIsNamedLensModel) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("NearestLens.* (the start it fits from), DiagnosisMatches.NoEffectNamesNothingDespiteOutliersAndIrregularGyro (the fit)");
  SimConfig c = wide(21);
  c.nominal.cam.fx = c.nominal.cam.fy = 340;  // the corners 67 degrees off the axis
  const Distortion fisheye = Distortion::equidistant(0.02, -0.01, 0.003, -0.001);
  c.nominal.cam.dist = nearest_lens(fisheye, LensModel::PinholeRadtan, corner_angle(c.nominal.cam));
  c.effects.lens = fisheye;
  const Diagnosis d = run(c);
  EXPECT_EQ(names(d), "lens_model ");
  const NamedEffect* e = find(d, "lens_model");
  EXPECT_EQ(text_param(e, "model"), "pinhole-equi");
  const double field = corner_angle(c.nominal.cam);
  const double before = lens_difference_px(c.nominal.cam.dist, fisheye, 340, field);
  const double after = lens_difference_px(named_lens(e, LensModel::PinholeEqui), fisheye, 340, field);
  std::printf("lens against the truth: nominal %.3f px, named %.3f px\n", before, after);
  EXPECT_GT(before, 1.5);  // what the pinhole stand-in misses, in the worst corner
  EXPECT_LT(after, 0.3 * before);
}

TEST(DiagnosisLens, APinholeBehindAnEquidistantNominalIsNamedLensModel) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("NearestLens.* (the start it fits from), DiagnosisMatches.NoEffectNamesNothingDespiteOutliersAndIrregularGyro (the fit)");
  SimConfig c = wide(22);
  c.nominal.cam.dist = Distortion::equidistant(0, 0, 0, 0);  // a fisheye profile for a pinhole camera
  c.effects.lens = Distortion{};                              // the camera: a pinhole without distortion
  const Diagnosis d = run(c);
  EXPECT_EQ(names(d), "lens_model ");
  const NamedEffect* e = find(d, "lens_model");
  EXPECT_EQ(text_param(e, "model"), "pinhole-radtan");
  const double field = corner_angle(c.nominal.cam);
  EXPECT_LT(lens_difference_px(named_lens(e, LensModel::PinholeRadtan), Distortion{}, 400, field), 0.3);
}

TEST(DiagnosisLens, AnEquidistantNominalWithWrongTermsIsNamedLensDistortionK1ToK4) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("NearestLens.* (the equidistant terms), DiagnosisMatches.NoEffectNamesNothingDespiteOutliersAndIrregularGyro (the fit)");
  SimConfig c = wide(23);
  c.nominal.cam.dist = Distortion::equidistant(0.02, -0.01, 0, 0);
  c.effects.k1k2 = Eigen::Vector2d(0.06, -0.03);
  const Diagnosis d = run(c);
  EXPECT_EQ(names(d), "lens_distortion ");
  const NamedEffect* e = find(d, "lens_distortion");
  ASSERT_NE(e, nullptr);
  EXPECT_EQ(e->params.size(), 4u);  // k1..k4 of the equidistant lens
  const Distortion truth = Distortion::equidistant(0.06, -0.03, 0, 0);
  const double after = lens_difference_px(named_lens(e, LensModel::PinholeEqui), truth, 400, corner_angle(c.nominal.cam));
  std::printf("lens against the truth: named %.3f px\n", after);
  EXPECT_LT(after, 0.3);
}

}  // namespace test_diagnosis_lens
