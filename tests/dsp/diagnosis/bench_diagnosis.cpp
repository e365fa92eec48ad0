// The diagnosis's speed goal (issue 34, point 5), as a benchmark, not a timed test: a recording
// of one minute at 1920x1080 diagnosed in at most 20 s on one core, ten minutes in at most
// 3 minutes. The recordings are simulated like a phone's as rsd-extract writes them: 200
// matches per frame pair with 10% outliers, an irregular gyro on its own axes, no stated noise,
// a rolling shutter, a clock offset and a gyro bias to find. diagnose() runs on one thread.
// Usage: bench_diagnosis [MINUTES...]   (default: 1 10). Prints one line per recording.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/sim/recording_simulation.hpp"

using namespace rsd::dsp;

namespace {

SimConfig phone_1080p(double minutes) {
  SimConfig c;
  c.kind = ObservationKind::Matches;
  c.seed = 34;
  c.duration_s = 60 * minutes;
  c.start_time_s = 1000;
  c.nominal.cam.width = 1920, c.nominal.cam.height = 1080;
  c.nominal.cam.fx = c.nominal.cam.fy = 1450, c.nominal.cam.cx = 959.5, c.nominal.cam.cy = 539.5;
  c.nominal.frame_rate_hz = 30;
  c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  c.noise_px = 0.7;
  c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
  c.gyro = {20, 200, 0.01, 0.03, 0.0005, 0.002};
  c.matches_per_pair = 200;
  c.outlier_fraction = 0.1;
  c.effects.line_delay_s = 2e-5, c.effects.time_offset_s = 0.004;
  c.effects.gyro_bias = Eigen::Vector3d(0.01, -0.008, 0.012);
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<double> minutes;
  for (int k = 1; k < argc; ++k) minutes.push_back(std::atof(argv[k]));
  if (minutes.empty()) minutes = {1, 10};
  for (double min : minutes) {
    SimulatedRecording sim = simulate_recording(phone_1080p(min));
    sim.rec.noise_px.reset();  // as rsd-extract writes a recording: the noise is the data's
    const DiagnosisModel model(sim.rec);
    const auto t0 = std::chrono::steady_clock::now();
    const Diagnosis d = diagnose(model);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double goal = min <= 1 ? 20 : 180 * min / 10;
    std::string named;
    for (const NamedEffect& e : d.effects) named += (named.empty() ? "" : ", ") + e.name;
    std::printf("%.3g min at 1920x1080: %d observations (the fits saw %d), diagnosed in %.1f s (goal <= %.0f s: %s); named {%s}\n",
                min, model.size(), d.fit_observations, s, goal, s <= goal ? "MET" : "MISSED", named.c_str());
    std::fflush(stdout);
  }
  return 0;
}
