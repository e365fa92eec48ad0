#include "dsp/diagnosis/own_depth.hpp"

#include <algorithm>
#include <cmath>

#include "dsp/core/statistics.hpp"

namespace rsd::dsp {

std::vector<Eigen::Vector2d> own_depths(const std::vector<Eigen::Vector2d>& flow, const std::vector<Eigen::Vector2d>& left,
                                        double depth_px) {
  if (!(depth_px > 0)) return {};
  std::vector<Eigen::Vector2d> b(flow.size(), Eigen::Vector2d::Zero());
  for (size_t k = 0; k < flow.size(); ++k) {
    const double q = flow[k].squaredNorm() + depth_px * depth_px, e = flow[k].dot(left[k]) / q;
    // What share of a e it takes out (own_depth_kept); b b^T left = kept a e. None for a residual
    // that is not finite (a failed prediction): b stays zero.
    if (const double kept = own_depth_kept(e); kept > 0) b[k] = std::sqrt(kept) * flow[k] / std::sqrt(q);
  }
  return b;
}

double own_depth_kept(double e) {
  if (!std::isfinite(e)) return 0.0;
  if (e > kMaxOwnDepth) return kMaxOwnDepth / e;
  if (e < kMinOwnDepth) return kMinOwnDepth / e;
  return 1.0;
}

DepthSpread measured_spread(const std::vector<Eigen::Vector2d>& flow, const std::vector<Eigen::Vector2d>& left,
                            const std::vector<bool>& in, double noise) {
  double excess = 0, energy = 0;
  size_t used = 0;
  std::vector<double> flows;
  for (size_t k = 0; k < flow.size(); ++k) {
    if (!in[k]) continue;
    const Eigen::Vector2d& a = flow[k];
    flows.push_back(a.norm() / noise);
    if (a.norm() <= noise) continue;
    const Eigen::Vector2d along = a.normalized(), &r = left[k];
    const double x = along.dot(r), y = along.x() * r.y() - along.y() * r.x();
    excess += x * x - y * y, energy += a.squaredNorm(), ++used;
  }
  if (used == 0) return {};
  return {std::sqrt(std::max(0.0, excess / energy)), excess / (2 * noise * noise * std::sqrt(static_cast<double>(used))),
          median(flows)};
}

}  // namespace rsd::dsp
