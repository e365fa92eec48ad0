#include "dsp/diagnosis/model.hpp"

#include "dsp/diagnosis/gyro_stamps.hpp"
#include "dsp/diagnosis/match_jacobian.hpp"
#include "dsp/diagnosis/translation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_fixed_point.hpp"

namespace rsd::dsp {

const char* param_name(Param p) {
  static constexpr const char* kNames[] = {"line_delay_s", "time_offset_s", "drift_ppm", "k1", "k2", "fx", "fy",
                                           "x",            "y",             "z",         "bx", "by", "bz",
                                           "k3",           "k4",
                                           "rx",           "ry",            "rz",        "sx", "sy", "sz",
                                           "cx",           "cy"};
  static_assert(sizeof kNames / sizeof kNames[0] == kParamCount);
  return kNames[static_cast<int>(p)];
}

std::vector<Param> params_in(const ParamMask& mask) {
  std::vector<Param> out;
  for (int k = 0; k < kParamCount; ++k)
    if (mask[k]) out.push_back(Param(k));
  return out;
}

ModelParams with_translation_of(ModelParams p, const ModelParams& from) {
  p.translation_nuisance = from.translation_nuisance;
  p.translation_knot_s = from.translation_knot_s;
  p.translation_depth_px = from.translation_depth_px;
  p.translation_world_plane = from.translation_world_plane;
  p.translation_pair_shifts = from.translation_pair_shifts;
  return p;
}

ModelParams nominal_params(const NominalModel& n) {
  ModelParams p;
  p[Param::LineDelay] = n.time.line_delay_s;
  p[Param::TimeOffset] = n.time.time_offset_s;
  p[Param::Drift] = n.time.drift_ppm;
  set_lens_terms(p, n.cam.dist);
  p[Param::Fx] = n.cam.fx;
  p[Param::Fy] = n.cam.fy;
  for (int k = 0; k < 3; ++k) p.v[static_cast<int>(Param::LeverX) + k] = n.lever_arm[k];
  p[Param::ScaleX] = p[Param::ScaleY] = p[Param::ScaleZ] = 1.0;
  p[Param::Cx] = n.cam.cx;
  p[Param::Cy] = n.cam.cy;
  return p;  // gyro bias and mount rotation: the nominal model has none
}

std::optional<Follows> follows(Param q, const NominalModel& n) {
  if (q == Param::Fy) return Follows{Param::Fx, n.cam.fy / n.cam.fx};
  return std::nullopt;
}

void set_param(ModelParams& p, Param q, double v, const NominalModel& n) {
  p[q] = v;
  for (int k = 0; k < kParamCount; ++k)  // the parameters that follow q (fy follows fx)
    if (const std::optional<Follows> f = follows(static_cast<Param>(k), n); f && f->leader == q) p.v[k] = v * f->factor;
}

double param_scale(Param p, const NominalModel& n) {
  switch (p) {
    case Param::LineDelay: return 0.1 / (n.frame_rate_hz * n.cam.height);  // 10% of a full-frame readout
    case Param::TimeOffset: return 1e-3;
    case Param::Drift: return 10.0;
    case Param::K1:
    case Param::K2:
    case Param::K3:
    case Param::K4: return 0.01;
    case Param::Fx:
    case Param::Fy: return 1e-3 * n.cam.fx;
    case Param::BiasX:
    case Param::BiasY:
    case Param::BiasZ: return 1e-3;  // rad/s
    case Param::MountX:
    case Param::MountY:
    case Param::MountZ: return 1e-3;  // rad
    case Param::ScaleX:
    case Param::ScaleY:
    case Param::ScaleZ: return 1e-3;
    case Param::Cx:
    case Param::Cy: return 1.0;  // px
    default: return 0.01;  // lever arm, metres
  }
}

Eigen::Matrix3d mount_of(const ModelParams& p) {
  const Eigen::Vector3d r(p[Param::MountX], p[Param::MountY], p[Param::MountZ]);
  return r.isZero() ? Eigen::Matrix3d::Identity() : exp_so3(r);
}

LandmarkSetup landmark_setup(const NominalModel& n, const ModelParams& p) {
  LandmarkSetup s{n.cam, n.time, n.lever_arm};
  s.time.line_delay_s = p[Param::LineDelay];
  s.time.time_offset_s = p[Param::TimeOffset];
  s.time.drift_ppm = p[Param::Drift];
  if (p.flip_readout)
    s.time.readout = n.time.readout == Readout::TopToBottom ? Readout::BottomToTop : Readout::TopToBottom;
  s.cam.dist = lens_of(n, p);
  s.cam.fx = p[Param::Fx];
  s.cam.fy = p[Param::Fy];
  s.lever_arm = Eigen::Vector3d(p[Param::LeverX], p[Param::LeverY], p[Param::LeverZ]);
  s.mount = mount_of(p);
  s.cam.cx = p[Param::Cx];
  s.cam.cy = p[Param::Cy];
  return s;
}

void set_lens_terms(ModelParams& p, const Distortion& d) {
  p[Param::K1] = d.k1, p[Param::K2] = d.k2, p[Param::K3] = d.k3, p[Param::K4] = d.k4;
}

LensModel lens_family(const NominalModel& n, const ModelParams& p) {
  const LensModel nominal = n.cam.dist.model;
  if (!p.other_lens) return nominal;
  return nominal == LensModel::PinholeEqui ? LensModel::PinholeRadtan : LensModel::PinholeEqui;
}

// lens_distortion frees the nominal family's radial terms (radtan k1, k2: its tangential terms
// and k3 stay nominal; equi k1..k4); lens_model puts the other family's lens in its place.
Distortion lens_of(const NominalModel& n, const ModelParams& p) {
  if (lens_family(n, p) == LensModel::PinholeEqui)
    return Distortion::equidistant(p[Param::K1], p[Param::K2], p[Param::K3], p[Param::K4]);
  Distortion d = p.other_lens ? Distortion{} : n.cam.dist;
  d.k1 = p[Param::K1], d.k2 = p[Param::K2];
  return d;
}

// The few gyro tracks last asked for, newest first: a Jacobian under the translation nuisance
// asks for the base bias and one perturbation per bias and scale axis (the translation pass
// at each), over and over.
struct DiagnosisModel::TrackCache {
  std::vector<std::unique_ptr<GyroTrack>> tracks;
};

// The rays of frame_a's pixels for the last few cameras, each computed when first asked for: the
// fits' trial points and the uncertainties' differences ask for the same cameras again and
// again, and undistorting every pixel anew cost a tenth of a diagnosis.
struct DiagnosisModel::RayCache {
  struct Slot {
    CameraModel cam;
    std::vector<Eigen::Vector3d> ray;
    std::vector<unsigned char> state;  // 0 not yet, 1 ray, 2 none (no undistortion there)
    const Eigen::Vector3d* get(int i) {
      if (state[i] == 0) {
        const auto r = cam.ray(px_a->at(i));
        state[i] = r ? 1 : 2;
        if (r) ray[i] = *r;
      }
      return state[i] == 1 ? &ray[i] : nullptr;
    }
    const std::vector<Eigen::Vector2d>* px_a = nullptr;
  };
  std::vector<Eigen::Vector2d> px_a;  // per observation
  std::vector<Slot> slots;            // newest first
  Slot& slot(const CameraModel& c) {
    auto same = [&](const Slot& s) {
      return s.cam.fx == c.fx && s.cam.fy == c.fy && s.cam.cx == c.cx && s.cam.cy == c.cy && s.cam.dist == c.dist;
    };
    for (size_t k = 0; k < slots.size(); ++k)
      if (same(slots[k])) {
        std::rotate(slots.begin(), slots.begin() + k, slots.begin() + k + 1);
        return slots.front();
      }
    if (slots.size() < 4) slots.emplace_back();
    std::rotate(slots.begin(), slots.end() - 1, slots.end());  // the oldest (or the new one) first
    Slot& s = slots.front();
    s.cam = c, s.px_a = &px_a;
    s.ray.resize(px_a.size());
    s.state.assign(px_a.size(), 0);
    return s;
  }
};

DiagnosisModel::DiagnosisModel(const DiagnosisModel& m, std::vector<GyroSample> gyro)
    : rec_(m.rec_), t0_(m.t0_), gyro_(std::move(gyro)), max_gap_(m.max_gap_), stamps_(m.stamps_), obs_(m.obs_),
      tracks_(std::make_unique<TrackCache>()), rays_(std::make_unique<RayCache>()) {
  if (m.rec_.kind != ObservationKind::Matches || gyro_.size() != m.gyro_.size())
    throw std::invalid_argument("diagnosis: another gyro record applies to a matches recording, sample for sample");
  rays_->px_a = m.rays_->px_a;
}

DiagnosisModel::~DiagnosisModel() = default;

namespace {

void check_motion(const Recording& r) {
  if (r.kind == ObservationKind::Landmarks && (r.motion != MotionKind::Trajectory || r.trajectory.empty()))
    throw std::invalid_argument("diagnosis: a landmarks recording needs motion kind trajectory with poses");
  if (r.kind == ObservationKind::Matches && (r.motion != MotionKind::Gyro || r.gyro.empty()))
    throw std::invalid_argument("diagnosis: a matches recording needs motion kind gyro with samples");
}

SampledTrajectory sampled(const Recording& r) {
  std::vector<SampledTrajectory::Sample> s;
  s.reserve(r.trajectory.size());
  for (const PoseSample& p : r.trajectory) s.push_back({p.t, p.q, p.p});
  std::stable_sort(s.begin(), s.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  return SampledTrajectory(std::move(s));
}

}  // namespace

DiagnosisModel::DiagnosisModel(const Recording& rec)
    : rec_(rec), tracks_(std::make_unique<TrackCache>()), rays_(std::make_unique<RayCache>()) {
  check_motion(rec);
  if (rec.kind == ObservationKind::Landmarks) body_.emplace(rec.trajectory), body_slow_.emplace(sampled(rec));
  if (rec.frames.empty()) throw std::invalid_argument("diagnosis: the recording has no frames");
  std::vector<FrameStamp> frames = rec.frames;
  std::sort(frames.begin(), frames.end(), [](const FrameStamp& a, const FrameStamp& b) { return a.t < b.t; });
  t0_ = frames.front().t;
  std::unordered_map<int, std::pair<double, int>> frame;
  for (size_t k = 0; k < frames.size(); ++k) frame[frames[k].frame] = {frames[k].t, static_cast<int>(k)};
  if (rec.kind == ObservationKind::Landmarks) {
    std::unordered_map<int, Eigen::Vector3d> point;
    for (const Landmark& L : rec.points) point[L.id] = L.X;
    obs_->reserve(rec.observations.size());
    for (const LandmarkObservation& o : rec.observations) {
      const auto f = frame.find(o.frame);
      const auto X = point.find(o.id);
      if (f == frame.end() || X == point.end())
        throw std::invalid_argument("diagnosis: an observation names an unknown frame or point");
      obs_->push_back({f->second.first, f->second.first, f->second.second, X->second, o.px, o.px});
    }
    return;
  }
  gyro_ = clean_gyro(rec.gyro);
  max_gap_ = gyro_gap_limit(gyro_);
  // The stamps' jitter turns a rate's integral by the rate's change over the error, pair by
  // pair; where the rates hold the samples' times, they are taken from there.
  GyroStamps stamps = estimate_gyro_stamps(gyro_, max_gap_);
  gyro_ = std::move(stamps.gyro);
  stamps_ = stamps.spread;
  obs_->reserve(rec.matches.size());
  for (const Match& mt : rec.matches) {
    const auto a = frame.find(mt.frame_a), b = frame.find(mt.frame_b);
    if (a == frame.end() || b == frame.end()) throw std::invalid_argument("diagnosis: a match names an unknown frame");
    obs_->push_back({a->second.first, b->second.first, a->second.second, Eigen::Vector3d::Zero(), mt.b, mt.a});
    rays_->px_a.push_back(mt.a);
  }
}

const GyroTrack& DiagnosisModel::track(const Eigen::Vector3d& bias, const Eigen::Vector3d& scale) const {
  auto& v = tracks_->tracks;
  for (size_t k = 0; k < v.size(); ++k)
    if (v[k]->bias() == bias && v[k]->scale() == scale) {
      std::rotate(v.begin(), v.begin() + k, v.begin() + k + 1);
      return *v.front();
    }
  if (v.size() >= 6) v.pop_back();
  v.insert(v.begin(), std::make_unique<GyroTrack>(gyro_, bias, rec_.nominal.imu_to_camera, max_gap_, scale));
  return *v.front();
}

namespace {

Eigen::Vector3d bias_of(const ModelParams& p) { return {p[Param::BiasX], p[Param::BiasY], p[Param::BiasZ]}; }
Eigen::Vector3d scale_of(const ModelParams& p) { return {p[Param::ScaleX], p[Param::ScaleY], p[Param::ScaleZ]}; }

TimeModel with_t0(TimeModel tm, double t0) {
  tm.t0 = t0;
  return tm;
}

}  // namespace

std::optional<Eigen::Vector2d> DiagnosisModel::landmark_residual(const ModelParams& p, const Obs& o) const {
  LandmarkSetup s = landmark_setup(rec_.nominal, p);
  s.time = with_t0(s.time, t0_);
  const RowTiming rt = row_timing(s.time, s.cam.height);
  auto pixel_at = [&](double v) -> std::optional<Eigen::Vector2d> {
    // X_c = M^T R^T (X_w - p - R l) = M^T (R^T (X_w - p) - l): the camera axes are the body
    // axes turned by the mount M (spec mount_rotation: R_c = R Exp(r)).
    Eigen::Matrix3d R;
    Eigen::Vector3d p;
    body_->at(s.time.motion_time(o.T + rt.row_time(v)), R, p);
    return s.cam.project(s.mount.transpose() * (R.transpose() * (o.X - p) - s.lever_arm));
  };
  // The row by secant iteration from the observed one; where it does not settle, the
  // bracketing solver (rs_projection.hpp, case e).
  const auto solved = fixed_point_row(pixel_at, o.px.y());
  if (!solved) {
    const auto slow = predict_landmark(s, *body_slow_, o.T, o.X);
    if (!slow) return std::nullopt;
    return Eigen::Vector2d(o.px - slow->pixel);
  }
  return Eigen::Vector2d(o.px - solved->px);
}

struct DiagnosisModel::MatchSetup {
  LandmarkSetup s;  // camera and time model only
  TimeModel tm;
  RowTiming rt;
  Eigen::Matrix3d mount_t;
  RayCache::Slot* rays;
};

DiagnosisModel::MatchSetup DiagnosisModel::match_setup(const ModelParams& p) const {
  const LandmarkSetup s = landmark_setup(rec_.nominal, p);
  const TimeModel tm = with_t0(s.time, t0_);
  return {s, tm, row_timing(tm, s.cam.height), s.mount.transpose(), &rays_->slot(s.cam)};
}

std::optional<Eigen::Vector2d> DiagnosisModel::match_residual(const MatchSetup& ms, const GyroTrack& track, int i,
                                                              TrackHints& at, RowStart& row) const {
  const Obs& o = (*obs_)[i];
  const Eigen::Vector3d* ray = ms.rays->get(i);
  if (!ray) return std::nullopt;
  // Spec "Matches": the direction seen at frame_a's pixel, in world axes, at its row's time. A
  // mount rotation turns imu_to_camera into E R_nominal (E = Exp(r)): the camera's
  // world-from-camera rotation becomes track.camera_at(t) E^T.
  size_t &at_a = at.a, &at_b = at.b;
  const Eigen::Vector3d d = track.to_world(ms.tm.motion_time(o.T + ms.rt.row_time(o.px_a.y())), ms.mount_t * *ray, at_a);
  auto pixel_at = [&](double v) {
    return ms.s.cam.project(ms.s.mount * track.to_camera(ms.tm.motion_time(o.T_b + ms.rt.row_time(v)), d, at_b));
  };
  const bool near = std::isfinite(row.row);  // a nearby point's solution, else the observed row
  const auto solved = fixed_point_row(pixel_at, near ? row.row : o.px.y(),
                                      near ? row.slope : std::numeric_limits<double>::quiet_NaN());
  if (!solved) return std::nullopt;
  row.row = solved->row, row.slope = solved->slope;
  return Eigen::Vector2d(o.px - solved->px);
}

std::optional<Eigen::Vector2d> DiagnosisModel::residual(const ModelParams& p, int i) const {
  if (rec_.kind == ObservationKind::Landmarks) return landmark_residual(p, (*obs_)[i]);
  TrackHints at;
  RowStart row;
  return match_residual(match_setup(p), track(bias_of(p), scale_of(p)), i, at, row);
}

std::vector<Eigen::Vector2d> DiagnosisModel::residuals(const ModelParams& p, const std::vector<int>& idx) const {
  // Nothing kept: most callers (a held-out RMS, a criterion) look once and move on.
  return translation_out(p, idx, rotation_residuals(p, idx, nullptr, nullptr), nullptr);
}

std::vector<Eigen::Vector2d> DiagnosisModel::rotation_residuals(const ModelParams& p, const std::vector<int>& idx,
                                                                Settled* settled, const Settled* near) const {
  std::vector<Eigen::Vector2d> out;
  out.reserve(idx.size());
  const Eigen::Vector2d nan = Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN());
  if (rec_.kind == ObservationKind::Landmarks) {
    for (int i : idx) out.push_back(landmark_residual(p, (*obs_)[i]).value_or(nan));
    return out;
  }
  if (near && near->rows.size() != idx.size())
    throw std::invalid_argument("diagnosis: fixed points settled on other observations than these");
  const GyroTrack& tr = track(bias_of(p), scale_of(p));
  const MatchSetup ms = match_setup(p);
  if (settled) settled->rows.assign(idx.size(), RowStart{});
  TrackHints at;  // observations in order: the next one's frames are mostly the same or near
  for (size_t k = 0; k < idx.size(); ++k) {
    RowStart row = near ? near->rows[k] : RowStart{};
    out.push_back(match_residual(ms, tr, idx[k], at, row).value_or(nan));
    if (settled) settled->rows[k] = row;
  }
  return out;
}

std::vector<Eigen::Vector2d> DiagnosisModel::translation_out(const ModelParams& p, const std::vector<int>& idx,
                                                             std::vector<Eigen::Vector2d> r, TranslationFit* keep) const {
  if (rec_.kind != ObservationKind::Matches || !p.translation_nuisance) return r;
  const MatchSetup ms = match_setup(p);
  remove_translation(*this, idx, r, track(bias_of(p), scale_of(p)), ms.tm, ms.mount_t, p.translation_knot_s, keep,
                     p.translation_pair_shifts, p.translation_depth_px, p.translation_world_plane, &ms.s.cam);
  return r;
}

std::vector<Eigen::Vector2d> DiagnosisModel::residuals(const ModelParams& p, const std::vector<int>& idx,
                                                       Settled& settled, const Settled* rows_from) const {
  std::vector<Eigen::Vector2d> r = rotation_residuals(p, idx, &settled, rows_from);
  const bool nuisance = rec_.kind == ObservationKind::Matches && p.translation_nuisance;
  settled.rotation = nuisance ? r : std::vector<Eigen::Vector2d>{};
  // What settled there before is remove_translation's hint (its frame pairs' grouping).
  if (!nuisance) settled.translation.state.reset();
  return translation_out(p, idx, std::move(r), &settled.translation);
}

std::vector<Eigen::Vector2d> DiagnosisModel::residuals_near(const ModelParams& p, const std::vector<int>& idx,
                                                            const Settled& near) const {
  return translation_out_near(p, idx, rotation_residuals(p, idx, nullptr, &near), near);
}

std::vector<Eigen::Vector2d> DiagnosisModel::translation_out_near(const ModelParams& p, const std::vector<int>& idx,
                                                                  std::vector<Eigen::Vector2d> r,
                                                                  const Settled& near) const {
  if (rec_.kind != ObservationKind::Matches || !p.translation_nuisance) return r;
  const MatchSetup ms = match_setup(p);
  remove_fitted_translation(*this, idx, r, track(bias_of(p), scale_of(p)), ms.tm, ms.mount_t, p.translation_knot_s,
                            near.translation);
  return r;
}

void DiagnosisModel::translation_out_of_columns(const ModelParams& p, const std::vector<int>& idx, Eigen::MatrixXd& cols,
                                                const Settled& near) const {
  if (rec_.kind != ObservationKind::Matches || !p.translation_nuisance) return;
  const MatchSetup ms = match_setup(p);
  remove_fitted_translation_from_columns(*this, idx, cols, track(bias_of(p), scale_of(p)), ms.tm, ms.mount_t,
                                         p.translation_knot_s, near.translation);
}

bool DiagnosisModel::moves_translation_pass(Param q) {
  switch (q) {
    case Param::Fx: case Param::Fy: case Param::Cx: case Param::Cy:
    case Param::K1: case Param::K2: case Param::K3: case Param::K4:
      return false;
    default:
      return true;
  }
}

std::vector<MatchJacobian> DiagnosisModel::rotation_jacobian(const ModelParams& p, const std::vector<int>& idx,
                                                             const Settled& at, bool gyro) const {
  if (rec_.kind != ObservationKind::Matches || at.rows.size() != idx.size())
    throw std::invalid_argument("diagnosis: rotation_jacobian needs matches settled on the same observations");
  const GyroTrack& tr = track(bias_of(p), scale_of(p));
  const MatchSetup ms = match_setup(p);
  const double rate = 1 + ms.tm.drift_ppm * 1e-6;  // d motion_time / d t_camera
  const Eigen::Matrix3d mount_jr = so3_right_jacobian({p[Param::MountX], p[Param::MountY], p[Param::MountZ]});
  std::vector<MatchJacobian> out(idx.size(), MatchJacobian::Zero());
  // t = motion_time(T + row_time(v)), row_time linear in the line delay: row_time(v) = l f(v).
  auto clock = [&](double T, double v, double& t, Eigen::Vector3d& dt) {
    const double rt = ms.rt.row_time(v);
    t = ms.tm.motion_time(T + rt);
    dt = {rate * rt / ms.rt.line_delay_s, 1.0, 1e-6 * (T + rt - t0_)};
  };
  TrackHints at_hint;
  for (size_t k = 0; k < idx.size(); ++k) {
    const Obs& o = (*obs_)[idx[k]];
    const Eigen::Vector3d* ray = ms.rays->get(idx[k]);
    if (!std::isfinite(at.rows[k].row) || !ray) continue;
    MatchAtSolution m;
    double ta, tb;
    clock(o.T, o.px_a.y(), ta, m.dta);
    clock(o.T_b, at.rows[k].row, tb, m.dtb);
    m.ray = *ray, m.mount = ms.s.mount, m.mount_jr = mount_jr, m.dtb_dv = rate / ms.rt.r();
    m.R_a = tr.camera_at(ta, at_hint.a, m.w_a, gyro ? &m.gyro_a : nullptr);
    m.R_b = tr.camera_at(tb, at_hint.b, m.w_b, gyro ? &m.gyro_b : nullptr);
    if (!gyro) m.gyro_a.setZero(), m.gyro_b.setZero();
    m.imu_to_camera = rec_.nominal.imu_to_camera;
    out[k] = -match_prediction_jacobian(ms.s.cam, m);
  }
  return out;
}

double DiagnosisModel::gyro_gap(const ModelParams& p, int i) const {
  if (rec_.kind != ObservationKind::Matches) return 0.0;
  const TimeModel tm = with_t0(landmark_setup(rec_.nominal, p).time, t0_);
  const Obs& o = (*obs_)[i];
  const double a = tm.motion_time(std::min(o.T, o.T_b)), b = tm.motion_time(std::max(o.T, o.T_b) + 1.0 / rec_.nominal.frame_rate_hz);
  auto lt = [](const GyroSample& g, double t) { return g.t < t; };
  // From the last sample at or before a to the first at or after b.
  auto lo = std::lower_bound(gyro_.begin(), gyro_.end(), a, lt);
  if (lo != gyro_.begin() && (lo == gyro_.end() || lo->t > a)) --lo;
  auto hi = std::lower_bound(gyro_.begin(), gyro_.end(), b, lt);
  if (hi == gyro_.end() || lo == gyro_.end()) return std::numeric_limits<double>::infinity();  // past the data
  // One more interval either side: its Hermite slopes come from the samples at these ends.
  if (lo != gyro_.begin()) --lo;
  if (hi + 1 != gyro_.end()) ++hi;
  double gap = 0;
  for (auto it = lo; it != hi; ++it) gap = std::max(gap, (it + 1)->t - it->t);
  return gap;
}

std::pair<double, double> DiagnosisModel::offset_range() const {
  // A frame's rows span at most one frame period; keep that whole window inside the data.
  double first = std::numeric_limits<double>::infinity(), last = -first;
  for (const FrameStamp& f : rec_.frames) first = std::min(first, f.t), last = std::max(last, f.t);
  const double period = 1.0 / rec_.nominal.frame_rate_hz;
  double lo, hi;
  if (rec_.kind == ObservationKind::Landmarks) {
    lo = rec_.trajectory.front().t, hi = rec_.trajectory.back().t;
    for (const PoseSample& s : rec_.trajectory) lo = std::min(lo, s.t), hi = std::max(hi, s.t);
  } else {
    lo = gyro_.front().t, hi = gyro_.back().t;
  }
  return {lo - first, hi - last - period};
}

}  // namespace rsd::dsp
