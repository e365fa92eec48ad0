#include "tools/report/diagnosis_suite.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "tools/common/cli_util.hpp"
#include "tools/report/diagnosis_report.hpp"
#include "dsp/diagnosis/diagnosis.hpp"

namespace rsd::tools {

using namespace rsd::dsp;

namespace {

bool applies(const std::string& effect, ObservationKind k) {
  if (effect == "gyro_bias" || effect == "gyro_scale") return k == ObservationKind::Matches;
  // The principal point: landmarks (in matches a rotation moves every pixel nearly alike, and a
  // principal point shift barely changes a transfer).
  if (effect == "lever_arm" || effect == "principal_point") return k == ObservationKind::Landmarks;
  return true;
}

}  // namespace

std::string SuiteCase::name() const {
  std::string s;
  for (const auto& e : effects) s += (s.empty() ? "" : " + ") + e;
  if (!preset.empty()) s = preset + ": " + s;
  if (!outside.empty()) s = "outside: " + outside + (s.empty() ? "" : " + " + s);
  if (s.empty()) return "none";
  return speed ? "speed (" + format_number(duration_s) + " s): " + s : s;
}

std::string SuiteCase::key() const {
  if (!preset.empty()) return preset;
  std::string s = outside.empty() ? "" : "outside:" + outside;
  for (const auto& e : effects) s += (s.empty() ? "" : "+") + e;
  return s.empty() ? "none" : s;
}

namespace {

// FNV-1a of "kind: effects".
unsigned case_seed(const SuiteCase& c) {
  uint32_t h = 2166136261u;
  for (char ch : std::string(dsp::to_string(c.kind)) + ": " + c.name()) h = (h ^ static_cast<uint8_t>(ch)) * 16777619u;
  return 1 + h % 1000000;
}

}  // namespace

std::vector<SuiteCase> suite_cases(bool reduced, const std::vector<ObservationKind>& kinds) {
  std::vector<SuiteCase> out;
  for (ObservationKind k : kinds) {
    const bool lm = k == ObservationKind::Landmarks;
    const std::string third = lm ? "lever_arm" : "gyro_bias";
    std::vector<std::vector<std::string>> sets;
    if (reduced) {
      // CI: no effect, the two pairs (rolling shutter against a time shift and against the
      // lens), and the kind's own effect in the triple. Matches leave the first pair to the
      // triple: on a short recording the gyro's shared per-frame errors put a one-sigma line
      // delay's 3% goal near its statistical limit (the full suite runs it).
      sets = {{}, {"rolling_shutter", "lens_distortion"}, {"rolling_shutter", "time_offset", third}};
      if (lm) sets.insert(sets.begin() + 1, {"rolling_shutter", "time_offset"});
      if (!lm) sets.erase(sets.begin() + 1);
      // The revised spec's effects: the principal point head to head with the mount rotation
      // and the lever arm (landmarks), the gyro scale with the focal length (matches).
      sets.push_back({lm ? "principal_point" : "gyro_scale"});
    } else {
      sets = {{}};
      for (const char* e : {"rolling_shutter", "readout_direction", "time_offset", "clock_drift", "lens_distortion",
                            "focal_length", "gyro_bias", "lever_arm", "mount_rotation", "gyro_scale", "principal_point"})
        if (applies(e, k)) sets.push_back({e});
      sets.push_back({"rolling_shutter", "time_offset"});
      sets.push_back({"rolling_shutter", "lens_distortion"});
      sets.push_back({"rolling_shutter", "time_offset", third});
    }
    // The seed follows from the case alone, so a reduced run reproduces the full table's rows.
    for (const auto& set : sets) {
      SuiteCase c;
      c.kind = k, c.effects = set;
      c.seed = case_seed(c);
      out.push_back(c);
    }
    // Physics outside the table: a significant remainder, and no effect named in its stead.
    std::vector<std::string> outside = {"clock_jump"};
    if (!lm) outside = reduced ? std::vector<std::string>{"parallax"}
                               : std::vector<std::string>{"parallax", "gyro_saturation", "clock_jump"};
    for (const auto& what : outside) {
      SuiteCase c;
      c.kind = k, c.outside = what;
      c.seed = case_seed(c);
      out.push_back(c);
    }
  }
  // Rigs of their own (matches): the phone with everything off at once, and fast rotation.
  if (std::find(kinds.begin(), kinds.end(), ObservationKind::Matches) != kinds.end()) {
    SuiteCase phone, fast;
    phone.kind = fast.kind = ObservationKind::Matches;
    phone.effects = {"rolling_shutter", "time_offset", "lens_distortion", "focal_length", "mount_rotation"};
    phone.preset = "phone";
    fast.effects = {"rolling_shutter", "time_offset"};
    fast.preset = "fast";
    for (SuiteCase* c : {&phone, &fast}) {
      c->seed = case_seed(*c);
      if (!reduced || c == &fast) out.push_back(*c);
    }
  }
  for (ObservationKind k : kinds)
    if (!reduced) {
      SuiteCase c;
      c.kind = k, c.effects = {"rolling_shutter", "time_offset", k == ObservationKind::Landmarks ? "lever_arm" : "gyro_bias"};
      c.seed = case_seed(c) + 1;  // another recording than the triple's row
      c.duration_s = kSpeedDurationS, c.speed = true;
      out.push_back(c);
    }
  return out;
}

double default_duration_s(bool) { return 20.0; }

SimConfig base_config(ObservationKind kind, double duration_s, unsigned seed) {
  SimConfig c;
  c.kind = kind;
  c.seed = seed;
  c.nominal.cam.width = 1920, c.nominal.cam.height = 1080;
  c.nominal.cam.cx = 959.5, c.nominal.cam.cy = 539.5;
  c.nominal.frame_rate_hz = 30;
  if (kind == ObservationKind::Landmarks) {
    // Like config/scenarios/landmarks-rolling-shutter.yaml: a 7x9 target, hand-held.
    c.nominal.cam.fx = c.nominal.cam.fy = 1329.75;
    c.duration_s = duration_s;
    c.start_time_s = 100;
    c.noise_px = 0.5;
    c.translation_amplitude_m = 0.08, c.rotation_amplitude_rad = 0.12, c.motion_frequency_hz = 1.0;
    c.trajectory_rate_hz = 500;
    c.target_rows = 7, c.target_cols = 9, c.target_spacing_m = 0.1, c.target_distance_m = 1.2;
  } else {
    // Like config/scenarios/matches-phone.yaml: an irregular gyro on its own axes, outliers.
    c.nominal.cam.fx = c.nominal.cam.fy = 1450;
    c.duration_s = duration_s;
    c.start_time_s = 1000;
    c.noise_px = 0.7;
    c.rotation_amplitude_rad = 0.25, c.motion_frequency_hz = 1.2;
    c.nominal.imu_to_camera << 0, -1, 0, -1, 0, 0, 0, 0, -1;
    c.gyro = {20, 200, 0.01, 0.03, 0.0005, 0.002};
    c.matches_per_pair = 120;
    c.outlier_fraction = 0.1;
  }
  return c;
}

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

// Physics outside the table, at a size a real rig shows: parallax of a wall 4 m away past a
// hand-held translation of 5 cm (a few pixels per frame pair), a gyro clipping at 1 rad/s
// (the hand-held motion peaks near 2), a clock that jumps by 3 ms half-way.
void apply_outside(SimConfig& c, const std::string& what) {
  if (what.empty()) return;
  if (what == "parallax") {
    c.unmodelled.scene_depth_m = 4.0;
    c.translation_amplitude_m = 0.05;
  } else if (what == "gyro_saturation") {
    c.unmodelled.gyro_saturation_rad_s = 1.0;
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
  } else {
    throw std::invalid_argument("unknown preset " + preset);
  }
}

double max_size(const std::string& e) {
  // A readout cannot exceed the frame period.
  return (e == "rolling_shutter" || e == "readout_direction") ? 1.0 : std::numeric_limits<double>::infinity();
}

std::optional<ModelParams> true_params(const SimulatedRecording& sim);

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

// ---------------------------------------------------------------- checks

const NamedEffect* find_effect(const Diagnosis& d, const std::string& name) {
  for (const auto& e : d.effects)
    if (e.name == name) return &e;
  return nullptr;
}

std::optional<double> value(const NamedEffect* e, const std::string& p) {
  if (!e) return std::nullopt;
  for (const auto& x : e->params)
    if (x.name == p && x.text.empty()) return x.value;
  return std::nullopt;
}

std::string text_value(const NamedEffect* e, const std::string& p) {
  if (!e) return "";
  for (const auto& x : e->params)
    if (x.name == p) return x.text;
  return "";
}

std::string pct(double err, double truth) {
  std::ostringstream o;
  o.setf(std::ios::showpos);
  o << format_number(100 * err / std::abs(truth), 2) << "%";  // + = above the truth
  return o.str();
}

// "value +- sigma" for a parameter, with its sigma from the report's uncertainties.
std::string with_sigma(double v, const std::vector<ParamUncertainty>& u, const std::string& effect,
                       const std::string& param, double unit, int digits = 4) {
  std::string s = format_number(v / unit, digits);
  for (const auto& p : u)
    if (p.effect == effect && p.param == param && p.sigma) s += " +- " + format_number(*p.sigma / unit, 2);
  return s;
}

EffectCheck check_effect(const std::string& e, const Effects& t, const NominalModel& n, const Diagnosis& d,
                         const std::vector<ParamUncertainty>& u) {
  EffectCheck c{e, 0, "", "not named", false};
  const NamedEffect* f = find_effect(d, e);
  // `offset`: what the recovered values are compared after subtracting (gyro scale: 1).
  auto vec_check = [&](const Eigen::Vector3d& truth, const char* names[3], double unit, double tol, const char* u_name,
                       double offset = 0.0) {
    std::ostringstream tr, re;
    tr << "(" << format_number(truth.x() / unit, 3) << ", " << format_number(truth.y() / unit, 3) << ", "
       << format_number(truth.z() / unit, 3) << ") " << u_name;
    c.truth = tr.str();
    double worst = 0;
    bool all = true;
    re << "(";
    for (int k = 0; k < 3; ++k) {
      auto v = value(f, names[k]);
      if (v) *v -= offset;
      all = all && v.has_value();
      if (v) worst = std::max(worst, std::abs(*v - truth[k]));
      re << (k ? ", " : "") << (v ? with_sigma(*v, u, e, names[k], unit, 3) : "?");
    }
    re << ") " << u_name << ", max error " << format_number(worst / unit, 2) << " " << u_name;
    if (f) c.recovered = re.str();
    c.ok = f && all && worst <= tol;
  };
  if (e == "rolling_shutter") {
    const double truth = *t.line_delay_s;
    c.truth = "line delay " + format_number(truth * 1e6, 4) + " us (readout " +
              format_number(truth * n.cam.height * 1e3, 3) + " ms)";
    if (const auto v = value(f, "line_delay_s")) {
      c.recovered = with_sigma(*v, u, e, "line_delay_s", 1e-6) + " us (" + pct(*v - truth, truth) + ")";
      c.ok = std::abs(*v - truth) <= 0.03 * truth;
    }
  } else if (e == "readout_direction") {
    const bool down = (n.time.readout == Readout::TopToBottom) != t.flip_readout;
    c.truth = down ? "top_to_bottom" : "bottom_to_top";
    c.truth += " (nominal line delay " + format_number(n.time.line_delay_s * 1e6, 3) + " us)";
    if (f) {
      const std::string got = text_value(f, "direction");
      c.recovered = got;
      c.ok = got == (down ? "top_to_bottom" : "bottom_to_top");
    }
  } else if (e == "time_offset") {
    const double truth = *t.time_offset_s;
    c.truth = format_number(truth * 1e3, 4) + " ms";
    if (const auto v = value(f, "time_offset_s")) {
      c.recovered = with_sigma(*v, u, e, "time_offset_s", 1e-3) + " ms (" + format_number((*v - truth) * 1e3, 2) + " ms)";
      c.ok = std::abs(*v - truth) <= 0.5e-3;
    }
  } else if (e == "clock_drift") {
    const double truth = *t.drift_ppm;
    c.truth = format_number(truth, 4) + " ppm";
    if (const auto v = value(f, "drift_ppm")) {
      c.recovered = with_sigma(*v, u, e, "drift_ppm", 1.0) + " ppm (" + pct(*v - truth, truth) + ")";
      c.ok = std::abs(*v - truth) <= 0.15 * std::abs(truth);
    }
  } else if (e == "lens_distortion") {
    const double truth = t.k1k2->x();
    c.truth = "k1 " + format_number(truth, 4) + ", k2 " + format_number(t.k1k2->y(), 3);
    if (const auto v = value(f, "k1")) {
      c.recovered = "k1 " + with_sigma(*v, u, e, "k1", 1.0) + " (" + pct(*v - truth, truth) + "), k2 " +
                    format_number(value(f, "k2").value_or(NAN), 3);
      c.ok = std::abs(*v - truth) <= 0.10 * std::abs(truth);
    }
  } else if (e == "focal_length") {
    const Eigen::Vector2d truth = *t.fxfy;
    c.truth = "fx " + format_number(truth.x(), 6) + ", fy " + format_number(truth.y(), 6) + " px (nominal " +
              format_number(n.cam.fx, 6) + ")";
    const auto fx = value(f, "fx"), fy = value(f, "fy");
    if (fx && fy) {
      c.recovered = "fx " + with_sigma(*fx, u, e, "fx", 1.0, 6) + " (" + pct(*fx - truth.x(), truth.x()) + "), fy " +
                    with_sigma(*fy, u, e, "fy", 1.0, 6) + " (" + pct(*fy - truth.y(), truth.y()) + ")";
      c.ok = std::abs(*fx - truth.x()) <= 0.002 * truth.x() && std::abs(*fy - truth.y()) <= 0.002 * truth.y();
    }
  } else if (e == "gyro_bias") {
    const char* names[3] = {"bx", "by", "bz"};
    vec_check(*t.gyro_bias, names, 1e-3, 1e-3, "mrad/s");
  } else if (e == "lever_arm") {
    const char* names[3] = {"x", "y", "z"};
    vec_check(*t.lever_arm, names, 1e-3, 1e-2, "mm");
  } else if (e == "mount_rotation") {
    const char* names[3] = {"rx", "ry", "rz"};
    vec_check(*t.mount_rotation, names, 1e-3, 2e-3, "mrad");
  } else if (e == "gyro_scale") {
    const char* names[3] = {"sx", "sy", "sz"};
    vec_check(*t.gyro_scale - Eigen::Vector3d::Ones(), names, 1e-3, 4e-3, "1e-3", 1.0);
  } else if (e == "principal_point") {
    const Eigen::Vector2d truth = *t.principal_point;
    c.truth = "cx " + format_number(truth.x(), 6) + ", cy " + format_number(truth.y(), 6) + " px (nominal " +
              format_number(n.cam.cx, 6) + ", " + format_number(n.cam.cy, 6) + ")";
    const auto cx = value(f, "cx"), cy = value(f, "cy");
    if (cx && cy) {
      c.recovered = "cx " + with_sigma(*cx, u, e, "cx", 1.0, 6) + ", cy " + with_sigma(*cy, u, e, "cy", 1.0, 6) +
                    " (error " + format_number(std::hypot(*cx - truth.x(), *cy - truth.y()), 2) + " px)";
      c.ok = std::abs(*cx - truth.x()) <= 0.5 && std::abs(*cy - truth.y()) <= 0.5;
    }
  }
  return c;
}

// The true model as diagnosis parameters, if every true effect has a parameter in it.
std::optional<ModelParams> true_params(const SimulatedRecording& sim) {
  ModelParams p = nominal_params(sim.rec.nominal);
  const Effects& t = sim.truth;
  if (t.line_delay_s) p[Param::LineDelay] = *t.line_delay_s;
  p.flip_readout = t.flip_readout;
  if (t.time_offset_s) p[Param::TimeOffset] = *t.time_offset_s;
  if (t.drift_ppm) p[Param::Drift] = *t.drift_ppm;
  if (t.k1k2) p[Param::K1] = t.k1k2->x(), p[Param::K2] = t.k1k2->y();
  if (t.fxfy) p[Param::Fx] = t.fxfy->x(), p[Param::Fy] = t.fxfy->y();
  auto set3 = [&](const std::optional<Eigen::Vector3d>& v, const char* a, const char* b, const char* c) {
    const char* names[3] = {a, b, c};
    for (int k = 0; k < 3 && v; ++k) {
      const auto q = param_by_name(names[k]);
      if (!q) return false;
      p[*q] = (*v)[k];
    }
    return true;
  };
  if (!set3(t.lever_arm, "x", "y", "z") || !set3(t.gyro_bias, "bx", "by", "bz") ||
      !set3(t.mount_rotation, "rx", "ry", "rz") || !set3(t.gyro_scale, "sx", "sy", "sz"))
    return std::nullopt;
  if (t.principal_point) p[Param::Cx] = t.principal_point->x(), p[Param::Cy] = t.principal_point->y();
  return p;
}

void run_checks(CaseResult& r, const DiagnosisModel& m, const SimulatedRecording& sim, const Diagnosis& d) {
  const std::vector<ParamUncertainty>& u = d.uncertainties;
  for (auto& c : r.checks) {
    const double shift = c.shift_sigmas;
    c = check_effect(c.effect, sim.truth, sim.rec.nominal, d, u);
    c.shift_sigmas = shift;
  }
  for (const auto& e : d.effects) r.named.push_back(e.name);
  std::vector<std::string> want = sim.truth.names(), got = r.named;
  std::sort(want.begin(), want.end());
  std::sort(got.begin(), got.end());
  r.names_ok = want == got;
  // Noise floor: what the true model leaves on the held-out observations.
  std::vector<int> held = d.heldout_indices;
  if (held.empty())
    for (int i = 0; i < m.size(); ++i)
      if (held_out(m, i, kHeldoutEvery)) held.push_back(i);
  if (const auto tp = true_params(sim)) {
    r.floor_px = robust_stats(m.residuals(*tp, held)).rms_px;
    r.floor_is_true_model = true;
  } else {
    r.floor_px = sim.rec.noise_px.value_or(0);
  }
  r.heldout_baseline_px = d.heldout_baseline_rms_px;
  r.heldout_final_px = d.heldout_final_rms_px;
  r.heldout_ok = d.heldout_final_rms_px <= 1.1 * r.floor_px;
  r.remainder_significant = d.remainder.significant;
  r.remainder_rms_px = d.remainder.rms_px;
  r.remainder_expected_px = d.remainder.expected_rms_px;
  if (!d.remainder.located.empty()) r.remainder_where = d.remainder.located.front().signal;
  r.remainder_ok = d.remainder.significant == !r.c.outside.empty();
}

}  // namespace

bool CaseResult::pass() const {
  if (!error.empty()) return false;
  for (const auto& c : checks)
    if (!c.ok) return false;
  return names_ok && heldout_ok && remainder_ok && (!c.speed || seconds < kSpeedLimitS);
}

CaseResult run_case(const SuiteCase& c, double duration_s, const std::string& report_dir) {
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
    const Diagnosis d = diagnose(m);
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
