#include "dsp/diagnosis/plausibility.hpp"

#include <cmath>
#include <sstream>

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
    case Effect::FocalLength: {
      const double a = std::abs(p[Param::Fx] / p[Param::Fy] - 1);
      x.beyond = over(a, 0.01, 0.002);
      o << "fx and fy differ by " << 100 * a << "%: pixels are square to within 1%";
      break;
    }
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

}  // namespace rsd::dsp
