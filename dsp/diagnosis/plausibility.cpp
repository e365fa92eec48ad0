#include "dsp/diagnosis/plausibility.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/select.hpp"

namespace rsd::dsp {

namespace {

struct Excess {
  double beyond = 0;  // how far past the bound, in widths (0: within)
  std::string why;
};

double over(double value, double bound, double width) { return value > bound ? (value - bound) / width : 0.0; }

Excess excess(const ModelParams& p, Effect e) {
  std::ostringstream o;
  Excess x;
  switch (e) {
    case Effect::GyroBias: {
      const double b = Eigen::Vector3d(p[Param::BiasX], p[Param::BiasY], p[Param::BiasZ]).norm();
      x.beyond = over(b, 0.1, 0.02);
      o << "a gyro bias of " << b * 1e3 << " mrad/s: a MEMS gyro's stays within 100 mrad/s";
      break;
    }
    case Effect::GyroScale: {
      double worst = 0;
      for (Param q : {Param::ScaleX, Param::ScaleY, Param::ScaleZ}) worst = std::max(worst, std::abs(p[q] - 1));
      x.beyond = over(worst, 0.05, 0.01);
      o << "a gyro scale " << 100 * worst << "% off: a MEMS gyro's is within 5%";
      break;
    }
    case Effect::ClockDrift: {
      const double d = std::abs(p[Param::Drift]);
      x.beyond = over(d, 1000, 250);
      o << "a clock drift of " << p[Param::Drift] << " ppm: a camera's and an IMU's clocks run within 1000 ppm of each other";
      break;
    }
    case Effect::LeverArm: {
      const double l = Eigen::Vector3d(p[Param::LeverX], p[Param::LeverY], p[Param::LeverZ]).norm();
      x.beyond = over(l, 0.5, 0.1);
      o << "a lever arm of " << l << " m: a camera sits within 0.5 m of its tracked origin";
      break;
    }
    default: break;
  }
  if (x.beyond > 0) x.why = o.str();
  return x;
}

}  // namespace

double implausibility(const ModelParams& p, const std::vector<Effect>& effects) {
  double c = 0;
  for (Effect e : effects) {
    const double b = excess(p, e).beyond;
    c += b * b;
  }
  return c;
}

std::string implausible_because(const ModelParams& p, Effect e) { return excess(p, e).why; }

std::string beyond_hardware_because(const ModelParams& p, Effect e, const DiagnosisModel& m) {
  // Past the soft bound by more than two widths (a gyro scale 7% off, a bias of 140 mrad/s, a
  // clock drift of 1500 ppm):
  // between, BIC's penalty weighs the evidence; beyond, no evidence makes it real hardware.
  if (const Excess x = excess(p, e); x.beyond > 2) return x.why;
  const NominalModel& n = m.recording().nominal;
  std::ostringstream o;
  if (e == Effect::FocalLength) {
    const double off = std::max(std::abs(p[Param::Fx] / n.cam.fx - 1), std::abs(p[Param::Fy] / n.cam.fy - 1));
    if (off > 0.25) {
      // Said to the user who gave that nominal: where a focal length this far off is the
      // strongest structure, the nominal is the likelier error (a guessed lens), not the camera.
      o.precision(3);
      o << "a focal length of " << p[Param::Fx] << " px, " << 100 * off << "% from the nominal " << n.cam.fx
        << " px: a lens is known to within 25% (if the nominal is a guess, give the lens's own: rsd-calib import-lens)";
      return o.str();
    }
  }
  return "";
}

std::string unnameable_because(const ModelParams& p, Effect e, const DiagnosisModel& m) {
  if (std::string why = beyond_hardware_because(p, e, m); !why.empty()) return why;
  const NominalModel& n = m.recording().nominal;
  std::ostringstream o;
  const ParamMask mask = effect_params(e, n.cam.dist.model);
  for (int k = 0; k < kParamCount; ++k) {
    if (!mask[k]) continue;
    const Param q = Param(k);
    const auto [lo, hi] = param_bounds(q, m);
    const double v = p[q], tol = 1e-3 * (hi - lo);
    const bool at_lo = v <= lo + tol && q != Param::LineDelay, at_hi = v >= hi - tol;
    if (at_lo || at_hi)
      return o << param_name(q) << " = " << v << " is at the bound of its range [" << lo << ", " << hi
               << "]: the data push it there, they do not measure it",
             o.str();
  }
  return "";
}

}  // namespace rsd::dsp
