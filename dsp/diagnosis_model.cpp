#include "dsp/diagnosis_model.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>

namespace rsd::dsp {

const char* param_name(Param p) {
  static constexpr const char* kNames[] = {"line_delay_s", "time_offset_s", "drift_ppm", "k1", "k2",
                                           "fx",           "fy",            "x",         "y", "z"};
  return kNames[static_cast<int>(p)];
}

ModelParams nominal_params(const NominalModel& n) {
  ModelParams p;
  p[Param::LineDelay] = n.time.line_delay_s;
  p[Param::TimeOffset] = n.time.time_offset_s;
  p[Param::Drift] = n.time.drift_ppm;
  p[Param::K1] = n.cam.dist.k1;
  p[Param::K2] = n.cam.dist.k2;
  p[Param::Fx] = n.cam.fx;
  p[Param::Fy] = n.cam.fy;
  for (int k = 0; k < 3; ++k) p.v[static_cast<int>(Param::LeverX) + k] = n.lever_arm[k];
  return p;
}

double param_scale(Param p, const NominalModel& n) {
  switch (p) {
    case Param::LineDelay: return 0.1 / (n.frame_rate_hz * n.cam.height);  // 10% of a full-frame readout
    case Param::TimeOffset: return 1e-3;
    case Param::Drift: return 10.0;
    case Param::K1:
    case Param::K2: return 0.01;
    case Param::Fx:
    case Param::Fy: return 1e-3 * n.cam.fx;
    default: return 0.01;  // lever arm, metres
  }
}

LandmarkSetup landmark_setup(const NominalModel& n, const ModelParams& p) {
  LandmarkSetup s{n.cam, n.time, n.lever_arm};
  s.time.line_delay_s = p[Param::LineDelay];
  s.time.time_offset_s = p[Param::TimeOffset];
  s.time.drift_ppm = p[Param::Drift];
  if (p.flip_readout)
    s.time.readout = n.time.readout == Readout::TopToBottom ? Readout::BottomToTop : Readout::TopToBottom;
  s.cam.dist.k1 = p[Param::K1];
  s.cam.dist.k2 = p[Param::K2];
  s.cam.fx = p[Param::Fx];
  s.cam.fy = p[Param::Fy];
  s.lever_arm = Eigen::Vector3d(p[Param::LeverX], p[Param::LeverY], p[Param::LeverZ]);
  return s;
}

namespace {

SampledTrajectory body_motion(const Recording& r) {
  if (r.kind != ObservationKind::Landmarks || r.motion != MotionKind::Trajectory || r.trajectory.empty())
    throw std::invalid_argument("diagnosis: only landmarks recordings with a trajectory are modelled so far");
  std::vector<SampledTrajectory::Sample> s;
  s.reserve(r.trajectory.size());
  for (const PoseSample& p : r.trajectory) s.push_back({p.t, p.q, p.p});
  return SampledTrajectory(std::move(s));
}

}  // namespace

DiagnosisModel::DiagnosisModel(const Recording& rec) : rec_(rec), body_(body_motion(rec)) {
  std::vector<FrameStamp> frames = rec.frames;
  std::sort(frames.begin(), frames.end(), [](const FrameStamp& a, const FrameStamp& b) { return a.t < b.t; });
  std::unordered_map<int, std::pair<double, int>> frame;
  for (size_t k = 0; k < frames.size(); ++k) frame[frames[k].frame] = {frames[k].t, static_cast<int>(k)};
  std::unordered_map<int, Eigen::Vector3d> point;
  for (const Landmark& L : rec.points) point[L.id] = L.X;
  obs_.reserve(rec.observations.size());
  for (const LandmarkObservation& o : rec.observations) {
    const auto f = frame.find(o.frame);
    const auto X = point.find(o.id);
    if (f == frame.end() || X == point.end())
      throw std::invalid_argument("diagnosis: an observation names an unknown frame or point");
    obs_.push_back({f->second.first, f->second.second, X->second, o.px});
  }
}

std::optional<Eigen::Vector2d> DiagnosisModel::residual(const ModelParams& p, int i) const {
  const Obs& o = obs_[i];
  const auto pred = predict_landmark(landmark_setup(rec_.nominal, p), body_, o.T, o.X);
  if (!pred) return std::nullopt;
  return Eigen::Vector2d(o.px - pred->pixel);
}

std::vector<Eigen::Vector2d> DiagnosisModel::residuals(const ModelParams& p, const std::vector<int>& idx) const {
  std::vector<Eigen::Vector2d> out;
  out.reserve(idx.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i : idx) out.push_back(residual(p, i).value_or(Eigen::Vector2d(nan, nan)));
  return out;
}

std::pair<double, double> DiagnosisModel::offset_range() const {
  // A frame's rows span at most one frame period; keep that whole window inside the data.
  double first = std::numeric_limits<double>::infinity(), last = -first;
  for (const FrameStamp& f : rec_.frames) first = std::min(first, f.t), last = std::max(last, f.t);
  const double period = 1.0 / rec_.nominal.frame_rate_hz;
  return {rec_.trajectory.front().t - first, rec_.trajectory.back().t - last - period};
}

}  // namespace rsd::dsp
