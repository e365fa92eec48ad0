// rsd-sim recording, read back: every example scenario's recording, as the CLI wrote it
// (tests/tools/sim.cmake), reads back through the rsd-recording/1 reader and equals the
// simulation done here in-process from the same scenario (a different code path: no CLI, no
// files). Nothing is lost or reordered in writing.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "dsp/sim/recording_simulation.hpp"
#include "formats/recording_v1.hpp"
#include "formats/scenario_file.hpp"

namespace rsd {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> scenarios() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(RSD_SCENARIO_DIR))
    if (e.path().extension() == ".yaml") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

class SimScenarioReadBack : public testing::TestWithParam<std::string> {};

TEST_P(SimScenarioReadBack, CliRecordingEqualsInProcessSimulation) {
  const std::string name = GetParam();
  const formats::Scenario sc = formats::load_scenario(std::string(RSD_SCENARIO_DIR) + "/" + name + ".yaml");
  const dsp::Recording want = dsp::simulate_recording(sc.sim).rec;
  const dsp::Recording got = formats::read_recording(std::string(RSD_SIM_OUT) + "/" + name);
  EXPECT_EQ(got.kind, want.kind);
  EXPECT_EQ(got.motion, want.motion);
  ASSERT_EQ(got.frames.size(), want.frames.size());
  for (size_t i = 0; i < want.frames.size(); ++i) {
    EXPECT_EQ(got.frames[i].frame, want.frames[i].frame);
    EXPECT_NEAR(got.frames[i].t, want.frames[i].t, 1e-9 * (1 + std::abs(want.frames[i].t)));
  }
  EXPECT_EQ(got.trajectory.size(), want.trajectory.size());
  EXPECT_EQ(got.gyro.size(), want.gyro.size());
  EXPECT_EQ(got.points.size(), want.points.size());
  ASSERT_EQ(got.observations.size(), want.observations.size());
  for (size_t i = 0; i < want.observations.size(); ++i) {
    EXPECT_EQ(got.observations[i].frame, want.observations[i].frame);
    EXPECT_EQ(got.observations[i].id, want.observations[i].id);
    EXPECT_LT((got.observations[i].px - want.observations[i].px).norm(), 1e-6) << "observation " << i;
  }
  ASSERT_EQ(got.matches.size(), want.matches.size());
  for (size_t i = 0; i < want.matches.size(); ++i) {
    EXPECT_EQ(got.matches[i].frame_a, want.matches[i].frame_a);
    EXPECT_EQ(got.matches[i].frame_b, want.matches[i].frame_b);
    EXPECT_LT((got.matches[i].a - want.matches[i].a).norm() + (got.matches[i].b - want.matches[i].b).norm(), 1e-6);
  }
  EXPECT_EQ(got.noise_px.has_value(), want.noise_px.has_value());
}

INSTANTIATE_TEST_SUITE_P(Examples, SimScenarioReadBack, testing::ValuesIn(scenarios()),
                         [](const testing::TestParamInfo<std::string>& p) {
                           std::string n = p.param;
                           for (char& c : n) if (c == '-') c = '_';
                           return n;
                         });

}  // namespace
}  // namespace rsd
