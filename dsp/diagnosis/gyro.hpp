// The camera orientation of a gyro recording (docs/formats/recording-v1.md, motion kind
// gyro) for one value of the gyro bias: the diagnosis re-integrates it whenever the fitted
// bias changes (a 20 s recording at 200 Hz integrates in well under a millisecond).
//
// Between samples the rate is the cubic Hermite curve through the neighbouring samples, and the
// orientation inside an interval is the partial integral of that curve (plus the Magnus
// commutator term), not a slerp between the sample orientations: at the 20 Hz end of an
// irregular gyro a slerp would be off by milliradians while the cubic stays within microradians.
// At the sample times the track equals integrate_gyro's (dsp/observation/observation_model.hpp).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <mutex>
#include <vector>

#include "dsp/observation/observation_model.hpp"

namespace rsd::dsp {

// Samples sorted by time; of samples sharing a timestamp only the first is kept: a repeated
// stamp is a later sample stamped late (its rate belongs to another time), and averaging it
// in would bend the rate curve. The rate is then a function of time, its slopes defined.
std::vector<GyroSample> clean_gyro(std::vector<GyroSample> gyro);

// The `percent`-th percentile of the intervals between consecutive samples of `gyro` (sorted,
// as clean_gyro returns it; at least two samples): the element at index n * percent / 100 of
// the n intervals in order.
double interval_percentile(const std::vector<GyroSample>& gyro, int percent);

// The longest interval between samples of `gyro` (sorted) that is still sampling, not a gap:
// 1.5 x the 95th percentile of the intervals, at least 20 ms (infinite under two samples).
double gyro_gap_limit(const std::vector<GyroSample>& gyro);

class GyroTrack {
 public:
  // `gyro` as clean_gyro returns it (at least one sample). w_true = w_measured - bias (spec
  // "gyro_bias"); w_camera = imu_to_camera w_imu.
  // Intervals longer than `max_interval` are gaps: a slope next to one comes from the
  // other side only (a neighbour across a gap says nothing about the rate's slope here).
  // `scale`: w_true = diag(scale) (w_measured - bias) (spec gyro_scale).
  GyroTrack(const std::vector<GyroSample>& gyro, const Eigen::Vector3d& bias, const Eigen::Matrix3d& imu_to_camera,
            double max_interval = std::numeric_limits<double>::infinity(),
            const Eigen::Vector3d& scale = Eigen::Vector3d::Ones());
  // World-from-camera rotation R_c(t) on the motion clock; held at the ends. With `hint` as
  // to_world's (below), for callers that walk through time.
  Eigen::Matrix3d camera_at(double t) const;
  Eigen::Matrix3d camera_at(double t, size_t& hint) const;
  // R_c(t) v and R_c(t)^T d without forming R_c(t): the diagnosis turns one direction per call,
  // and three matrix products (the interval's rotation, its exponential, the axes) cost more
  // than Rodrigues' formula on the vector itself. Equal to camera_at to rounding.
  // `hint`: the interval the caller's previous time fell in (any value at first): the fixed
  // point's iterations stay in one or two intervals, and the next observation's frame is mostly
  // the same or near, so the search starts there.
  Eigen::Vector3d to_world(double t, const Eigen::Vector3d& v, size_t& hint) const;
  Eigen::Vector3d to_camera(double t, const Eigen::Vector3d& d, size_t& hint) const;
  // camera_at with the caller's hint (as to_world's), and the camera's rate w_c (camera axes)
  // there, dR_c/dt = R_c [w_c]x: the derivative of the track itself (the Hermite rate with the
  // Magnus term's change, through the exponential's Jacobian), zero outside the data where the
  // track is held. With `by_gyro`, also how the track's IMU orientation turns with the gyro's
  // bias and scale: R_imu(t) -> R_imu(t) Exp(G (d bias, d scale)), G its 3 x 6 matrix (IMU
  // axes), the derivative of the track's own integration (knot by knot, through each step's
  // exponential), not of the continuous motion. The diagnosis's analytic Jacobian
  // (match_jacobian.hpp) uses both.
  // The camera's rate at t (camera axes, bias- and scale-corrected): the Hermite rate through
  // the knots, to first order in the turn since the interval's knot (camera_at's rate without
  // the exponential's Jacobian and the Magnus term: cheaper, where a direction is all that is
  // asked); zero outside the data. `hint` as to_world's.
  Eigen::Vector3d rate_at(double t, size_t& hint) const;
  using ByGyro = Eigen::Matrix<double, 3, 6>;
  Eigen::Matrix3d camera_at(double t, size_t& hint, Eigen::Vector3d& rate, ByGyro* by_gyro = nullptr) const;
  const Eigen::Vector3d& bias() const { return bias_; }
  const Eigen::Vector3d& scale() const { return scale_; }
  double t_begin() const { return knots_.front().t; }
  double t_end() const { return knots_.back().t; }

 private:
  struct Knot {
    double t;
    Eigen::Matrix3d R;     // world-from-IMU at t
    Eigen::Vector3d w, s;  // bias-free rate and its slope
  };
  // Per knot, R -> R Exp(G (d bias, d scale)) (camera_at's by_gyro): integrated on the first
  // call that asks (a track is built for every bias the fits try, most never asked), once.
  const std::vector<ByGyro>& knots_by_gyro() const;
  mutable std::once_flag by_gyro_once_;
  mutable std::vector<ByGyro> by_gyro_;
  // d(step over the first share tau of the interval from knot a)/d(bias, scale).
  ByGyro step_by_gyro(const Knot& a, const Knot& b, double tau) const;
  // The knot whose interval holds t (knots_.front() before, knots_.back() after the data) and
  // the rotation vector from it to t (zero outside the data).
  const Knot& interval(double t, Eigen::Vector3d& phi, size_t& hint) const;
  // The knot index k with knots_[k].t <= t < knots_[k + 1].t, for t inside the data, into `hint`.
  void locate(double t, size_t& hint) const;
  static constexpr int kWalk = 8;  // intervals walked from the hint before a search
  std::vector<Knot> knots_;
  Eigen::Vector3d bias_, scale_;
  Eigen::Matrix3d imu_to_camera_t_;  // R_ic^T: R_c = R_imu R_ic^T
  Eigen::Matrix3d imu_to_camera_;    // R_ic
};

}  // namespace rsd::dsp
