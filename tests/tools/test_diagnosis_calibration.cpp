// rsd-diagnose --write-calibration's content: a simulated recording with a known line delay and
// time offset (nominal: global shutter, no offset) is diagnosed; the calibration composed from
// the diagnosis, written and read back, carries the truth within the diagnosis' accuracy, the
// nominal values where no effect was named, and each key's sigma from the fit.
#include <gtest/gtest.h>

#include "dsp/geometry/camera_motion.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "formats/calibration_v1.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/support/temp_dir.hpp"
#include "tools/report/diagnosis_calibration.hpp"
#include "tests/support/sanitizer.hpp"

namespace rsd {
namespace {

const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_diagnosis_calibration_");

TEST(DiagnosisCalibration, TheFileCarriesWhatTheDiagnosisFound) {
  dsp::SimConfig c = test::simulation(dsp::ObservationKind::Landmarks, 6, 1.0, 0.5);
  test::small_target(c);
  c.effects.line_delay_s = 4e-5;
  c.effects.time_offset_s = -0.01;
  const dsp::SimulatedRecording sim = dsp::simulate_recording(c);
  const dsp::Diagnosis d = dsp::diagnose(sim.rec);
  const std::string path = g_tmp.path("cal.yaml");
  formats::write_calibration(path, tools::calibration_from(sim.rec, d, "test"));
  const formats::Calibration cal = formats::read_calibration(path);
  EXPECT_NEAR(cal.line_delay_s, 4e-5, 0.03 * 4e-5);
  EXPECT_NEAR(cal.timeshift_cam_imu_s, -0.01, 5e-4);
  // Not named: the nominal values, exactly.
  EXPECT_EQ(cal.cam.fx, sim.rec.nominal.cam.fx);
  EXPECT_EQ(cal.cam.width, sim.rec.nominal.cam.width);
  EXPECT_EQ(cal.drift_ppm, 0.0);
  EXPECT_EQ(cal.imu_to_camera, sim.rec.nominal.imu_to_camera);
  EXPECT_EQ(cal.readout, sim.rec.nominal.time.readout);
  // The fit's sigmas: positive, and the truth within 4 of them.
  ASSERT_EQ(cal.sigma.count("line_delay_s"), 1u);
  ASSERT_EQ(cal.sigma.count("timeshift_cam_imu"), 1u);
  const double sl = cal.sigma.at("line_delay_s")[0], st = cal.sigma.at("timeshift_cam_imu")[0];
  EXPECT_GT(sl, 0);
  EXPECT_GT(st, 0);
  EXPECT_LT(std::abs(cal.line_delay_s - 4e-5), 4 * sl);
  EXPECT_LT(std::abs(cal.timeshift_cam_imu_s + 0.01), 4 * st);
  EXPECT_EQ(cal.sigma.count("drift_ppm"), 0u);  // not fitted: no sigma
}

// A mount rotation goes into T_cam_imu: gyro recordings as Exp(r) R_nominal (w_cam = R w_imu),
// trajectory recordings as Exp(r)^T (R_c = R Exp(r): body-to-camera is its transpose); the
// daemon then turns the gyro's (or the body's) rates into the camera's true ones.
TEST(DiagnosisCalibration, MountRotationComposesIntoTheImuRotation) {
  RSD_SKIP_LONG_IN_SLOW_BUILD("DiagnosisCalibration.TheFileCarriesWhatTheDiagnosisFound (the same diagnosis to file)");
  dsp::SimConfig g = test::simulation(dsp::ObservationKind::Matches, 21, 4.0, 0.5);
  g.matches_per_pair = 100;
  g.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  g.rotation_amplitude_rad = 0.25, g.motion_frequency_hz = 1.2;
  const Eigen::Vector3d r(0.024, -0.016, 0.03);
  g.effects.mount_rotation = r;
  const dsp::SimulatedRecording sg = dsp::simulate_recording(g);
  const formats::Calibration cg = tools::calibration_from(sg.rec, dsp::diagnose(sg.rec), "test");
  const Eigen::Matrix3d want_g = dsp::exp_so3(r) * g.nominal.imu_to_camera;
  EXPECT_LT((cg.imu_to_camera - want_g).cwiseAbs().maxCoeff(), 0.003) << cg.imu_to_camera;

  dsp::SimConfig t = test::simulation(dsp::ObservationKind::Landmarks, 23, 3.0, 0.5);
  test::small_target(t);
  const Eigen::Vector3d rt(0.0008, -0.0006, 0.004);
  t.effects.mount_rotation = rt;
  const dsp::SimulatedRecording st = dsp::simulate_recording(t);
  const formats::Calibration ct = tools::calibration_from(st.rec, dsp::diagnose(st.rec), "test");
  EXPECT_LT((ct.imu_to_camera - dsp::exp_so3(rt).transpose()).cwiseAbs().maxCoeff(), 0.002) << ct.imu_to_camera;
}

// --write-calibration writes the lens named: lens_model's family with its four terms
// (distortion_model: equidistant), lens_distortion's terms in the nominal family.
TEST(DiagnosisCalibration, TheNamedLensAndItsFamilyGoIntoTheFile) {
  dsp::SimConfig c = test::simulation(dsp::ObservationKind::Matches, 3, 1.0, 0.5);
  const dsp::SimulatedRecording sim = dsp::simulate_recording(c);  // a pinhole-radtan nominal
  dsp::Diagnosis d;
  d.fitted = dsp::nominal_params(sim.rec.nominal);
  d.fitted.other_lens = true;
  d.fitted[dsp::Param::K1] = 0.021, d.fitted[dsp::Param::K2] = -0.012;
  d.fitted[dsp::Param::K3] = 0.0031, d.fitted[dsp::Param::K4] = -0.0009;
  const std::string path = g_tmp.path("lens.yaml");
  formats::write_calibration(path, tools::calibration_from(sim.rec, d, "test"));
  const formats::Calibration cal = formats::read_calibration(path);
  EXPECT_EQ(cal.cam.dist, dsp::Distortion::equidistant(0.021, -0.012, 0.0031, -0.0009));

  d.fitted = dsp::nominal_params(sim.rec.nominal);  // lens_distortion: radtan k1, k2; the rest nominal
  d.fitted[dsp::Param::K1] = -0.07, d.fitted[dsp::Param::K2] = 0.01;
  formats::write_calibration(path, tools::calibration_from(sim.rec, d, "test"));
  dsp::Distortion want = sim.rec.nominal.cam.dist;
  want.k1 = -0.07, want.k2 = 0.01;
  EXPECT_EQ(formats::read_calibration(path).cam.dist, want);
}

}  // namespace
}  // namespace rsd
