#include "dsp/sim/flight_path.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "dsp/geometry/camera_motion.hpp"

namespace rsd::dsp {

namespace {

// 3x^2 - 2x^3 on [0, 1]: the pan starts and ends at rest.
double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

}  // namespace

std::vector<PoseSample> flight_poses(const FlightPath& f, double t_first_frame, double t_begin, double t_end) {
  std::vector<PoseSample> out;
  for (double t = t_begin; t <= t_end; t += 1e-3) {
    const double s = t - t_first_frame;
    const double yaw = f.pan_rad * smoothstep((s - f.pan_at_s) / f.pan_s);
    const Eigen::Vector3d shake = f.shake_rad * Eigen::Vector3d(std::sin(2 * M_PI * 2.3 * s),
                                                                0.75 * std::sin(2 * M_PI * 3.1 * s + 1),
                                                                0.5 * std::sin(2 * M_PI * 1.7 * s + 2));
    const Eigen::Quaterniond q =
        Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())) * Eigen::Quaterniond(exp_so3(shake));
    const Eigen::Vector3d p(f.drift_m * std::sin(0.7 * s), f.drift_m / 3 * std::sin(1.3 * s), f.speed_m_s * s);
    out.push_back({t, p, q.normalized()});
  }
  return out;
}

}  // namespace rsd::dsp
