#include "dsp/observation/observation_model.hpp"

#include <algorithm>
#include <stdexcept>

#include "dsp/geometry/rs_projection.hpp"

namespace rsd::dsp {

OrientationTrack::OrientationTrack(std::vector<Sample> samples) : samples_(std::move(samples)) {
  if (samples_.empty()) throw std::invalid_argument("OrientationTrack: no samples");
}

Eigen::Quaterniond OrientationTrack::at(double t) const {
  auto hi = std::upper_bound(samples_.begin(), samples_.end(), t,
                             [](double tt, const Sample& s) { return tt < s.t; });
  if (hi == samples_.begin()) return samples_.front().q;
  if (hi == samples_.end()) return samples_.back().q;
  const Sample& a = *(hi - 1);
  const Sample& b = *hi;
  const double dt = b.t - a.t;
  return dt > 0 ? a.q.slerp((t - a.t) / dt, b.q) : b.q;
}

namespace {

// Rate derivative at sample i from its distinct-time neighbours (one-sided at the ends).
Eigen::Vector3d rate_slope(const std::vector<GyroSample>& g, size_t i) {
  size_t lo = i, hi = i;
  while (lo > 0 && !(g[lo].t < g[i].t)) --lo;
  while (hi + 1 < g.size() && !(g[hi].t > g[i].t)) ++hi;
  if (lo == i && !(g[lo].t < g[i].t) && hi == i) return Eigen::Vector3d::Zero();
  const double dt = g[hi].t - g[lo].t;
  return dt > 0 ? Eigen::Vector3d((g[hi].w - g[lo].w) / dt) : Eigen::Vector3d::Zero();
}

}  // namespace

OrientationTrack integrate_gyro(const std::vector<GyroSample>& gyro, const Eigen::Vector3d& bias) {
  if (gyro.empty()) throw std::invalid_argument("integrate_gyro: no gyro samples");
  std::vector<OrientationTrack::Sample> out;
  out.reserve(gyro.size());
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  out.push_back({gyro.front().t, q});
  for (size_t i = 1; i < gyro.size(); ++i) {
    const double dt = gyro[i].t - gyro[i - 1].t;
    if (!(dt > 0)) continue;  // repeated (or out-of-order) stamp: no time passes
    const Eigen::Vector3d w0 = gyro[i - 1].w - bias, w1 = gyro[i].w - bias;
    // The rate as a cubic Hermite curve between the samples (slopes from the neighbours):
    // its integral is the trapezoid plus an end-slope correction, fourth order in dt. The
    // Magnus commutator term accounts for the rate turning within the interval.
    const Eigen::Vector3d integral =
        0.5 * dt * (w0 + w1) + dt * dt / 12.0 * (rate_slope(gyro, i - 1) - rate_slope(gyro, i));
    const Eigen::Vector3d phi = integral + dt * dt / 12.0 * w0.cross(w1);
    q = (q * Eigen::Quaterniond(exp_so3(phi))).normalized();
    out.push_back({gyro[i].t, q});
  }
  return OrientationTrack(std::move(out));
}

Eigen::Quaterniond camera_orientation(const Eigen::Quaterniond& q_imu, const Eigen::Matrix3d& imu_to_camera) {
  return (q_imu * Eigen::Quaterniond(imu_to_camera.transpose())).normalized();
}

RowTiming row_timing(const TimeModel& tm, int height) {
  RowTiming rt;
  rt.height = height;
  // A global shutter (line delay 0) is the limit of a very fast readout.
  rt.line_delay_s = tm.line_delay_s > 0 ? tm.line_delay_s : 1e-15;
  rt.readout = tm.readout;
  return rt;
}

namespace {

// Camera pose over time after the frame stamp T_k: t -> world_to_camera(t_m(T_k + t)).
class FrameMotion final : public CameraMotion {
 public:
  FrameMotion(const CameraMotion& world_to_body, const LandmarkSetup& s, double T_k)
      : body_(world_to_body), s_(s), T_k_(T_k) {}
  Eigen::Affine3d at(double t) const override {
    // X_c = M^T R^T (X_w - p - R l) = M^T (body(X_w) - l): the camera's axes are the body's
    // turned by the mount M (the identity unless the spec's mount_rotation is in).
    Eigen::Affine3d g = body_.at(s_.time.motion_time(T_k_ + t));
    g.translation() -= s_.lever_arm;
    g.linear() = s_.mount.transpose() * g.linear();
    g.translation() = s_.mount.transpose() * g.translation();
    return g;
  }

 private:
  const CameraMotion& body_;
  const LandmarkSetup& s_;
  double T_k_;
};

class FrameRotation final : public CameraMotion {
 public:
  FrameRotation(const OrientationTrack& track, const TimeModel& tm, double T) : track_(track), tm_(tm), T_(T) {}
  Eigen::Affine3d at(double t) const override {
    Eigen::Affine3d g = Eigen::Affine3d::Identity();
    g.linear() = track_.at(tm_.motion_time(T_ + t)).toRotationMatrix().transpose();
    return g;
  }

 private:
  const OrientationTrack& track_;
  const TimeModel& tm_;
  double T_;
};

std::optional<Prediction> solve(const CameraModel& cam, const TimeModel& tm, const CameraMotion& m, double T,
                                const Eigen::Vector3d& X) {
  const RowTiming rt = row_timing(tm, cam.height);
  const RsProjection p = project_trajectory(cam, rt, m, X);
  if (!p.ok()) return std::nullopt;
  return Prediction{p.pixel, T + p.t_c};
}

}  // namespace

std::optional<Prediction> predict_landmark(const LandmarkSetup& s, const CameraMotion& world_to_body, double T_k,
                                           const Eigen::Vector3d& X) {
  return solve(s.cam, s.time, FrameMotion(world_to_body, s, T_k), T_k, X);
}

std::optional<Eigen::Vector3d> world_direction(const MatchSetup& s, const OrientationTrack& camera_track, double T,
                                               const Eigen::Vector2d& pixel) {
  const auto ray = s.cam.ray(pixel);
  if (!ray) return std::nullopt;
  const RowTiming rt = row_timing(s.time, s.cam.height);
  const double t = T + rt.row_time(pixel.y());
  return camera_track.at(s.time.motion_time(t)) * ray->normalized();
}

std::optional<Prediction> predict_direction(const MatchSetup& s, const OrientationTrack& camera_track, double T,
                                            const Eigen::Vector3d& d_world) {
  return solve(s.cam, s.time, FrameRotation(camera_track, s.time, T), T, d_world);
}

std::optional<Prediction> predict_match(const MatchSetup& s, const OrientationTrack& camera_track, double T_a,
                                        const Eigen::Vector2d& pixel_a, double T_b) {
  const auto d = world_direction(s, camera_track, T_a, pixel_a);
  if (!d) return std::nullopt;
  return predict_direction(s, camera_track, T_b, *d);
}

}  // namespace rsd::dsp
