#include "dsp/analysis/paper_experiment.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

#include "dsp/geometry/rs_projection.hpp"

namespace rsd::dsp {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// SplitMix64 (Steele, Lea, Flood 2014) with our own uniform and Gaussian draws: unlike the
// standard library's distributions, whose algorithms are unspecified, it gives the same
// numbers with every compiler and library, so a seed names one experiment everywhere.
class Rng {
 public:
  Rng(std::uint64_t seed, std::uint64_t stream)
      : s_(mix(seed) ^ mix(stream + 0x632be59bd9b4e019ULL)) {}
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  double normal() {  // Box-Muller; 1 - u keeps the logarithm finite
    const double r = std::sqrt(-2.0 * std::log(1.0 - uniform()));
    return r * std::cos(2 * kPi * uniform());
  }
  // Function arguments are evaluated in an unspecified order: draw the coordinates one by one.
  Eigen::Vector2d normal2() {
    const double x = normal();
    return {x, normal()};
  }
  Eigen::Vector3d normal3() {
    const double x = normal(), y = normal();
    return {x, y, normal()};
  }
  Eigen::Vector3d unit_vector() {  // uniform on the sphere
    const double z = uniform(-1, 1), phi = uniform(0, 2 * kPi), s = std::sqrt(1 - z * z);
    return {s * std::cos(phi), s * std::sin(phi), z};
  }

 private:
  static std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  std::uint64_t next() { return mix(s_ += 0x9e3779b97f4a7c15ULL); }
  std::uint64_t s_;
};

// A unit vector perpendicular to u, uniformly random in angle about it.
Eigen::Vector3d random_perpendicular(const Eigen::Vector3d& u, Rng& rng) {
  const Eigen::Vector3d a = u.unitOrthogonal(), b = u.normalized().cross(a);
  const double phi = rng.uniform(0, 2 * kPi);
  return std::cos(phi) * a + std::sin(phi) * b;
}

// A camera at `centre` looking at the origin, rolled by a random angle about its axis:
// the world -> camera transform X_c = R (X - centre) as a RigidPose.
RigidPose look_at_origin(const Eigen::Vector3d& centre, Rng& rng) {
  const Eigen::Vector3d z = -centre.normalized();
  const Eigen::Vector3d x = random_perpendicular(z, rng);
  Eigen::Matrix3d R_wc;  // columns: the camera's axes in the world (x right, y down, z forward)
  R_wc << x, z.cross(x), z;
  RigidPose p;
  p.q = Eigen::Quaterniond(R_wc.transpose());
  p.t = -(p.q * centre);
  return p;
}

// Two cameras about 10 m from the cloud whose viewing directions differ by a random angle.
std::array<RigidPose, 2> place_cameras(const ExperimentSetup& s, Rng& rng) {
  const Eigen::Vector3d u1 = rng.unit_vector();
  const double angle = rng.uniform(s.view_angle_min_deg, s.view_angle_max_deg) * kDeg;
  const Eigen::Vector3d u2 = Eigen::AngleAxisd(angle, random_perpendicular(u1, rng)) * u1;
  const double d1 = rng.uniform(s.distance_min_m, s.distance_max_m);
  const double d2 = rng.uniform(s.distance_min_m, s.distance_max_m);
  const RigidPose c1 = look_at_origin(d1 * u1, rng);
  return {c1, look_at_origin(d2 * u2, rng)};
}

// Inside the image under eq. (4) at the given speed?
bool seen(const ExperimentSetup& s, const Eigen::Vector3d& Xc, double vy_kmh) {
  const RsProjection p = project_fronto_parallel(s.cam, s.timing, paper_motion(vy_kmh), Xc);
  return p.ok() && s.cam.contains(p.pixel, 0.0);
}

bool seen_by_both(const ExperimentSetup& s, const std::array<RigidPose, 2>& cams,
                  const Eigen::Vector3d& X) {
  for (const auto& c : cams)
    for (double v : {0.0, s.max_speed_kmh})
      if (!seen(s, c.apply(X), v)) return false;
  return true;
}

// Points uniform in the ball, kept when both cameras see them (world frame).
std::vector<Eigen::Vector3d> draw_points(const ExperimentSetup& s,
                                         const std::array<RigidPose, 2>& cams, Rng& rng) {
  std::vector<Eigen::Vector3d> pts;
  for (int attempts = 0; static_cast<int>(pts.size()) < s.points; ++attempts) {
    if (attempts > 1000 * s.points)
      throw std::invalid_argument("draw_trial: the cameras see too little of the point cloud");
    const double radius = s.cloud_radius_m * std::cbrt(rng.uniform());  // uniform in volume
    const Eigen::Vector3d X = radius * rng.unit_vector();
    if (seen_by_both(s, cams, X)) pts.push_back(X);
  }
  return pts;
}

// The truth in camera 1's frame: X1 = R1 X + t1, so camera 2 sees X2 = R2 R1^-1 (X1 - t1) + t2.
TwoViewEstimate relative_to_camera_1(const std::array<RigidPose, 2>& cams,
                                     const std::vector<Eigen::Vector3d>& world) {
  TwoViewEstimate e;
  e.cam2.q = cams[1].q * cams[0].q.inverse();
  e.cam2.t = cams[1].t - e.cam2.q * cams[0].t;
  for (const auto& X : world) e.points.push_back(cams[0].apply(X));
  return e;
}

TwoViewEstimate perturb(const ExperimentSetup& s, const TwoViewEstimate& truth, Rng& rng) {
  TwoViewEstimate e = truth;
  e.cam2.q = truth.cam2.q *
             Eigen::Quaterniond(Eigen::AngleAxisd(s.init_rotation_deg * kDeg, rng.unit_vector()));
  // Rotating t about an axis perpendicular to it turns its direction by exactly that angle
  // and keeps its length, the gauge.
  e.cam2.t =
      Eigen::AngleAxisd(s.init_direction_deg * kDeg, random_perpendicular(truth.cam2.t, rng)) *
      truth.cam2.t;
  for (auto& X : e.points) X += s.init_point_sigma_m * rng.normal3();
  return e;
}

ModelErrors evaluate(const ExperimentSetup& s, const TrialDraw& draw, const TwoViewData& data,
                     ProjectionModel model) {
  TwoViewBaOptions opt;
  opt.model = model;
  opt.huber_px = s.huber_px;
  const TwoViewBaResult r = two_view_bundle_adjust(data, draw.initial, opt);
  return {r.rms_px, rotation_error_deg(draw.truth.cam2.q, r.estimate.cam2.q),
          direction_error_deg(draw.truth.cam2.t, r.estimate.cam2.t), r.converged};
}

ModelSummary summarize_model(const std::vector<TrialErrors>& trials, ProjectionModel model) {
  const auto m = static_cast<size_t>(model);
  std::vector<double> reproj, rot, trans;
  ModelSummary s;
  for (const auto& t : trials) {
    reproj.push_back(t[m].reproj_px);
    rot.push_back(t[m].rot_deg);
    trans.push_back(t[m].trans_deg);
    s.not_converged += t[m].converged ? 0 : 1;
  }
  s.trials = static_cast<int>(trials.size());
  s.reproj_px = summarize(reproj);
  s.rot_deg = summarize(rot);
  s.trans_deg = summarize(trans);
  return s;
}

}  // namespace

TrialDraw draw_trial(const ExperimentSetup& setup, std::uint64_t seed, int trial) {
  Rng rng(seed, static_cast<std::uint64_t>(trial));
  const auto cams = place_cameras(setup, rng);
  TrialDraw d;
  d.truth = relative_to_camera_1(cams, draw_points(setup, cams, rng));
  d.initial = perturb(setup, d.truth, rng);
  for (auto& noise : d.unit_noise)
    for (int j = 0; j < setup.points; ++j) noise.push_back(rng.normal2());
  return d;
}

Twist paper_motion(double vy_kmh) {
  Twist tw;
  tw.v = Eigen::Vector3d(0, vy_kmh / 3.6, 0);
  return tw;
}

TwoViewData observe(const ExperimentSetup& setup, const TrialDraw& draw, double vy_kmh,
                    double sigma_px) {
  TwoViewData data{setup.cam, setup.timing, {paper_motion(vy_kmh), paper_motion(vy_kmh)}, {}};
  const RigidPose poses[2] = {RigidPose{}, draw.truth.cam2};
  for (int i = 0; i < 2; ++i)
    for (size_t j = 0; j < draw.truth.points.size(); ++j) {
      const RsProjection p = project_fronto_parallel(setup.cam, setup.timing, data.motion[i],
                                                     poses[i].apply(draw.truth.points[j]));
      if (!p.ok()) throw std::logic_error("observe: a drawn point has no rolling-shutter image");
      data.pixels[i].push_back(p.pixel + sigma_px * draw.unit_noise[i][j]);
    }
  return data;
}

double rotation_error_deg(const Eigen::Quaterniond& truth, const Eigen::Quaterniond& estimate) {
  // |log(R0^-1 R_hat)| is the angle of the relative rotation; Eigen takes it as
  // 2 atan2(|vec|, |w|), accurate for tiny angles.
  return Eigen::AngleAxisd(truth.inverse() * estimate).angle() / kDeg;
}

double direction_error_deg(const Eigen::Vector3d& truth, const Eigen::Vector3d& estimate) {
  return std::atan2(truth.cross(estimate).norm(), truth.dot(estimate)) / kDeg;
}

TrialErrors run_trial(const ExperimentSetup& setup, const TrialDraw& draw, double vy_kmh,
                      double sigma_px) {
  const TwoViewData data = observe(setup, draw, vy_kmh, sigma_px);
  TrialErrors e;
  for (ProjectionModel m : {ProjectionModel::RollingShutter, ProjectionModel::Perspective})
    e[static_cast<size_t>(m)] = evaluate(setup, draw, data, m);
  return e;
}

Stats summarize(std::vector<double> v) {
  Stats s;
  if (v.empty()) return s;
  const double n = static_cast<double>(v.size());
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
  double ss = 0;
  for (double x : v) ss += (x - s.mean) * (x - s.mean);
  s.std = v.size() > 1 ? std::sqrt(ss / (n - 1)) : 0.0;
  std::sort(v.begin(), v.end());
  const size_t h = v.size() / 2;
  s.median = v.size() % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
  return s;
}

std::vector<Cell> paper_cells() {
  std::vector<Cell> cells;
  for (double v : kPaperSpeedsKmh)
    for (double s : kPaperSigmasPx) cells.push_back({v, s});
  return cells;
}

CellResult run_cell(const ExperimentSetup& setup, std::uint64_t seed, const Cell& cell,
                    int trials) {
  std::vector<TrialErrors> errors;
  for (int k = 0; k < trials; ++k)
    errors.push_back(run_trial(setup, draw_trial(setup, seed, k), cell.vy_kmh, cell.sigma_px));
  CellResult r{cell, {}};
  for (ProjectionModel m : {ProjectionModel::RollingShutter, ProjectionModel::Perspective})
    r.models[static_cast<size_t>(m)] = summarize_model(errors, m);
  return r;
}

}  // namespace rsd::dsp
