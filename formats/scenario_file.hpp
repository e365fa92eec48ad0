// rsd-sim scenarios: a YAML file that states the nominal camera, timing and motion, the
// scene, the observations, and which of recording-v1's named effects the "real" camera
// has (with their true parameters). See docs/simulator.md for every key.
#pragma once

#include <string>

#include "dsp/sim/recording_simulation.hpp"
#include "dsp/sim/calibration_target.hpp"

namespace rsd::formats {

struct Scenario {
  dsp::SimConfig sim;  // sim.points holds the target's landmarks
  dsp::TargetSpec target_spec;
  dsp::Target target;
  std::string file;
};

// Throws ConfigError naming file, line and key on any unknown key or bad value.
Scenario load_scenario(const std::string& file);

}  // namespace rsd::formats
