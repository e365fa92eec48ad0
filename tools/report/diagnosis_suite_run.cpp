// One case of the benchmark suite run: each effect scaled to move the observations by one noise
// sigma (or a preset rig's own sizes), physics outside the table added, the recording simulated
// and diagnosed, the goals checked (diagnosis_suite_checks.cpp) and, if asked, the report written.
#include "tools/report/diagnosis_suite.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "tools/report/diagnosis_report.hpp"
#include "tools/report/diagnosis_suite_checks.hpp"
#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/sim/flight_path.hpp"

namespace rsd::tools {

using namespace rsd::dsp;

// ---------------------------------------------------------------- calibration

namespace {

// Effect `e` at size `a` (dimensionless; 1 = the unit below) applied to `c`. The directions
// are fixed; the size is what calibration scales.
void apply(SimConfig& c, const std::string& e, double a) {
  const NominalModel& n = c.nominal;
  const double full_readout_line_delay = 1.0 / (n.frame_rate_hz * n.cam.height);
  const Eigen::Vector3d dir = Eigen::Vector3d(0.6, -0.48, 0.64).normalized();
  if (e == "rolling_shutter") {
    c.effects.line_delay_s = a * full_readout_line_delay;  // a = readout / frame period
  } else if (e == "readout_direction") {
    // The nominal model has the sensor's true line delay, but the wrong order of rows.
    c.nominal.time.line_delay_s = a * full_readout_line_delay;
    c.effects.flip_readout = true;
  } else if (e == "time_offset") {
    c.effects.time_offset_s = a * 1e-3;
  } else if (e == "clock_drift") {
    c.effects.drift_ppm = a * 100.0;
  } else if (e == "lens_distortion") {
    c.effects.k1k2 = Eigen::Vector2d(-0.01 * a, 0.0);  // barrel; k2 stays nominal (0)
  } else if (e == "focal_length") {
    c.effects.fxfy = Eigen::Vector2d(n.cam.fx, n.cam.fy) * (1 + 1e-3 * a);
  } else if (e == "gyro_bias") {
    c.effects.gyro_bias = 1e-3 * a * dir;  // rad/s
  } else if (e == "lever_arm") {
    c.effects.lever_arm = 1e-3 * a * dir;  // m
  } else if (e == "mount_rotation") {
    c.effects.mount_rotation = 1e-3 * a * dir;  // rad
  } else if (e == "gyro_scale") {
    c.effects.gyro_scale = Eigen::Vector3d::Ones() + 1e-3 * a * dir;
  } else if (e == "principal_point") {
    c.effects.principal_point = Eigen::Vector2d(n.cam.cx, n.cam.cy) + a * Eigen::Vector2d(0.8, -0.6);  // px
  } else {
    throw std::invalid_argument("unknown effect " + e);
  }
}

// Physics outside the table, at a size a real rig shows: parallax of a wall 4 m away (fixed in
// the world) past a hand-held translation of 5 cm (a few pixels per frame pair), a gyro clipping at 1 rad/s
// (the hand-held motion peaks near 2), a clock that jumps by 3 ms half-way, a video stabilised
// in the camera (its pictures follow the orientation smoothed at 5 Hz, zero phase: the 1.2 Hz
// shake keeps 94.5% of its swing, with no lag, so a gyro scale 5.5% low would stand in), and a
// drone's distant scene (40 m ahead: with the drone preset's forward flight, parallax in every pair).
void apply_outside(SimConfig& c, const std::string& what) {
  if (what.empty()) return;
  if (what == "parallax") {
    c.unmodelled.scene_depth_m = 4.0;
    c.translation_amplitude_m = 0.05;
    // Fixed in the world, as a wall is: it turns in the camera as the camera turns, which the
    // translation nuisance's plane (one per frame pair, lying the same way before each pair's
    // first frame) does not model, so the suite does not hold the diagnosis to its own assumption.
    c.unmodelled.scene_fixed_in_world = true;
  } else if (what == "distant_scene") {
    // A drone's view ahead: flow of a few pixels per pair at 8 m/s. It keeps its distance, as a
    // horizon does: a plane fixed in the world 40 m ahead would be flown through within the recording.
    c.unmodelled.scene_depth_m = 40.0;
  } else if (what == "gyro_saturation") {
    c.unmodelled.gyro_saturation_rad_s = 1.0;
  } else if (what == "stabilised") {
    c.unmodelled.stabilisation_hz = 5.0;
  } else if (what == "clock_jump") {
    c.unmodelled.clock_jump_s = 3e-3;
    c.unmodelled.clock_jump_at_s = 0.5 * c.duration_s;
  } else {
    throw std::invalid_argument("unknown physics outside the table: " + what);
  }
}

// A preset rig (SuiteCase::preset): its motion and noise, and its effects at the sizes a real
// rig has; with `only`, that one effect alone (for its shift column).
void apply_preset(SimConfig& c, const std::string& preset, const std::string& only = "") {
  const NominalModel& n = c.nominal;
  auto on = [&](const char* e) { return only.empty() || only == e; };
  if (preset == "phone") {
    // A phone: the nominal focal length 15% off, the clocks 0.4 s apart, a 25 ms readout,
    // barrel distortion, the camera turned a degree against the IMU.
    if (on("focal_length")) c.effects.fxfy = Eigen::Vector2d(n.cam.fx, n.cam.fy) * 1.15;
    if (on("time_offset")) c.effects.time_offset_s = 0.4;
    if (on("rolling_shutter")) c.effects.line_delay_s = 0.025 / n.cam.height;
    if (on("lens_distortion")) c.effects.k1k2 = Eigen::Vector2d(-0.06, 0.0);
    if (on("mount_rotation")) c.effects.mount_rotation = Eigen::Vector3d(0.6, -0.48, 0.64).normalized() * (M_PI / 180);
  } else if (preset == "fast") {
    // Fast rotation: 3-4 rad/s at its peaks, tens of pixels per frame; a 30 ms readout and a
    // 3 ms clock offset; matches good to 0.3 px, few outliers, a clean 200 Hz gyro.
    c.rotation_amplitude_rad = 0.5, c.motion_frequency_hz = 1.2;
    c.noise_px = 0.3;
    c.outlier_fraction = 0.02;
    c.gyro = {200, 200, 0, 0, 0, 0.002};
    if (on("rolling_shutter")) c.effects.line_delay_s = 0.030 / n.cam.height;
    if (on("time_offset")) c.effects.time_offset_s = 0.003;
  } else if (preset == "drone") {
    // A drone's gimbal camera flying forward at 8 m/s and panning 0.8 rad once (flight_path.hpp),
    // its own 400 Hz gyro; the clocks 58 ms apart (as in the Karma clip of issue 34), a 20 ms readout.
    c.motion_source = MotionSource::Samples;
    c.pose_samples = flight_poses(FlightPath{}, c.start_time_s, c.start_time_s - 3, c.start_time_s + c.duration_s + 3);
    c.gyro = {400, 400, 0, 0, 0, 0.002};
    if (on("time_offset")) c.effects.time_offset_s = -0.058;
    if (on("rolling_shutter")) c.effects.line_delay_s = 0.020 / n.cam.height;
  } else {
    throw std::invalid_argument("unknown preset " + preset);
  }
}

double max_size(const std::string& e) {
  // A readout cannot exceed the frame period.
  return (e == "rolling_shutter" || e == "readout_direction") ? 1.0 : std::numeric_limits<double>::infinity();
}

// Per-coordinate RMS by which the effects in `c` move the observations: how far the true
// model's predictions lie from the nominal model's, on a noise-free, outlier-free simulation.
// (Not the nominal residual itself: the gyro's jittered stamps leave a floor of their own.)
double shift_rms(SimConfig c) {
  c.noise_px = 0;
  c.outlier_fraction = 0;
  c.gyro.noise_rad_s = 0;
  const SimulatedRecording sim = simulate_recording(c);
  const DiagnosisModel m(sim.rec);
  const auto truth = true_params(sim);
  if (!truth) throw std::invalid_argument("diagnosis model: no parameter for an effect of this case");
  std::vector<int> all(m.size());
  for (int i = 0; i < m.size(); ++i) all[i] = i;
  const auto rn = m.residuals(nominal_params(sim.rec.nominal), all), rt = m.residuals(*truth, all);
  double s = 0;
  int n = 0;
  for (size_t k = 0; k < all.size(); ++k)
    if (rn[k].allFinite() && rt[k].allFinite()) s += (rn[k] - rt[k]).squaredNorm(), ++n;
  return n > 0 ? std::sqrt(s / (2.0 * n)) : 0.0;
}

// The size of effect `e` that moves the observations by one noise sigma (the shift is near
// linear in the size, so a few secant steps suffice); returns the size and the shift reached.
std::pair<double, double> calibrate(const SimConfig& base, const std::string& e) {
  double a = 1.0, shift = 0;
  const double target = base.noise_px;
  for (int it = 0; it < 4; ++it) {
    SimConfig c = base;
    apply(c, e, a);
    shift = shift_rms(c);
    if (std::abs(shift / target - 1) < 0.03 || !(shift > 0)) break;
    const double next = std::min(a * std::clamp(target / shift, 0.05, 20.0), max_size(e));
    if (next == a) break;
    a = next;
  }
  return {a, shift};
}

}  // namespace

CaseResult run_case(const SuiteCase& c, double duration_s, const std::string& report_dir,
                    const std::function<void(const std::string&)>& progress) {
  CaseResult r;
  r.c = c;
  try {
    SimConfig base = base_config(c.kind, c.duration_s > 0 ? c.duration_s : duration_s, c.seed);
    SimConfig cfg = base;
    if (!c.preset.empty()) {
      apply_preset(cfg, c.preset);
      base.noise_px = cfg.noise_px;
      for (const auto& e : c.effects) {
        SimConfig alone = base;
        apply_preset(alone, c.preset, e);
        r.checks.push_back({e, shift_rms(alone) / base.noise_px, "", "", false});
      }
    } else {
      for (const auto& e : c.effects) {
        const auto [a, shift] = calibrate(base, e);
        apply(cfg, e, a);
        r.checks.push_back({e, shift / base.noise_px, "", "", false});
      }
    }
    r.noise_px = base.noise_px;
    r.combined_shift_sigmas = c.effects.empty() ? 0 : shift_rms(cfg) / base.noise_px;
    apply_outside(cfg, c.outside);
    SimulatedRecording sim = simulate_recording(cfg);
    if (c.preset == "fast") sim.rec.noise_px.reset();  // as rsd-extract's recordings: the data must tell
    const auto t0 = std::chrono::steady_clock::now();
    const DiagnosisModel m(sim.rec);
    DiagnosisOptions options;
    options.progress = progress;
    const Diagnosis d = diagnose(m, options);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.observations = d.baseline.observations;
    run_checks(r, m, sim, d);
    if (!report_dir.empty())
      write_report(report_dir, {std::string("simulated: ") + dsp::to_string(c.kind) + " / " + c.name(), &m, &d,
                                kHeldoutEvery, r.seconds});
  } catch (const std::invalid_argument& e) {
    // The diagnosis model rejects recordings it cannot model ("diagnosis: ..."), e.g. a kind
    // not supported yet; anything else is a failure of the case.
    r.unsupported = std::string(e.what()).starts_with("diagnosis");
    r.error = (r.unsupported ? "unsupported: " : "") + std::string(e.what());
  } catch (const std::exception& e) {
    r.error = e.what();
  }
  return r;
}

}  // namespace rsd::tools
