// The benchmark suite's goals checked on a diagnosed case against its simulation's truth: each
// effect's parameter recovered within the tolerance, the named set exact, the held-out
// RMS near the noise floor, a significant remainder exactly when the case holds physics outside
// the table.
#include "tools/report/diagnosis_suite_checks.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "tools/common/cli_util.hpp"

namespace rsd::tools {

using namespace rsd::dsp;

namespace {

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

}  // namespace

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
    r.floor_px = robust_stats(m.residuals(heldout_model(d, *tp), held)).rms_px;  // as the diagnosis compared
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

bool CaseResult::pass() const {
  if (!error.empty()) return false;
  for (const auto& c : checks)
    if (!c.ok) return false;
  return names_ok && heldout_ok && remainder_ok && (!c.speed || seconds < kSpeedLimitS);
}

}  // namespace rsd::tools
