// rsd-diagnose --write-calibration's content: a simulated recording with a known line delay and
// time offset (nominal: global shutter, no offset) is diagnosed; the calibration composed from
// the diagnosis, written and read back, carries the truth within the diagnosis' accuracy, the
// nominal values where no effect was named, and each key's sigma from the fit.
#include <gtest/gtest.h>

#include "dsp/sim/recording_simulation.hpp"
#include "formats/calibration_v1.hpp"
#include "tests/dsp/diagnosis/diagnosis_configs.hpp"
#include "tests/support/temp_dir.hpp"
#include "tools/report/diagnosis_calibration.hpp"

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
  formats::write_calibration(path, tools::calibration_from(sim.rec.nominal, d, "test"));
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

}  // namespace
}  // namespace rsd
