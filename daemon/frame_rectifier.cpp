#include "daemon/frame_rectifier.hpp"

#include "dsp/analysis/applicability.hpp"

#include <chrono>
#include <cmath>
#include <numbers>
#include <thread>

namespace rsd::daemon {

dsp::CameraModel output_camera(const RectifyConfig& cfg, const dsp::CameraModel& captured) {
  if (cfg.output == RectifyOutput::SameLens) return captured;
  return dsp::CameraModel::from_hfov(captured.width, captured.height, cfg.output_hfov_deg * std::numbers::pi / 180);
}

FrameRectifier::FrameRectifier(const RectifyConfig& cfg, const dsp::CameraModel& cam, const dsp::RowTiming& timing,
                               const drivers::FrameFormat& fmt, dsp::RowExecutor* pool)
    : cfg_(cfg), cam_(cam), timing_(timing) {
  dsp::RectifierConfig rc;
  rc.initial_spacing = cfg.grid_px;
  rc.max_bands = pool ? dsp::RectifierConfig::bands_for(pool->concurrency()) : 1;
  rect_ = cfg.output == RectifyOutput::SameLens
              ? std::make_unique<dsp::Rectifier>(cam, timing, fmt.format, rc)
              : std::make_unique<dsp::Rectifier>(cam, timing, output_camera(cfg, cam), fmt.format, rc);
  rect_->set_executor(pool);
}

FrameRectifier::~FrameRectifier() = default;

dsp::DepthModel FrameRectifier::depth_model() const {
  switch (cfg_.depth) {
    case DepthKind::Infinite: return dsp::DepthModel::at_infinity();
    case DepthKind::Plane: return dsp::DepthModel::fronto_parallel(cfg_.depth_m);
    case DepthKind::Ground: return dsp::ground_plane(cfg_.camera_height_m);
  }
  return dsp::DepthModel::at_infinity();
}

void FrameRectifier::wait_for_samples(int64_t t_ns, const VelocityBuffer& velocity, uint64_t horizon,
                                      RectifyResult& r) const {
  using Clock = std::chrono::steady_clock;
  if (horizon == VelocityBuffer::kAll && velocity.newest_ns() < t_ns && cfg_.imu_wait_ms > 0) {
    const Clock::time_point start = Clock::now();
    const Clock::time_point until = start + std::chrono::microseconds(std::llround(cfg_.imu_wait_ms * 1e3));
    while (velocity.newest_ns() < t_ns && Clock::now() < until) std::this_thread::sleep_for(std::chrono::microseconds(100));
    r.imu_wait_s = std::chrono::duration<double>(Clock::now() - start).count();
  }
  const int64_t newest = velocity.newest_ns(horizon);
  if (newest != INT64_MIN && newest < t_ns) {
    r.extrapolated = true;
    r.extrapolated_s = static_cast<double>(t_ns - newest) * 1e-9;
  }
}

bool FrameRectifier::knots(const drivers::FrameMeta& meta, const VelocityBuffer& velocity, uint64_t horizon, bool translate,
                           dsp::IntegratedMotion::Knot* out) const {
  // Frame time t is first_row_ns + t s, as row_time() counts it; the knots span every row's
  // exposure, and the motion holds the end rates beyond them.
  const double a = std::min(timing_.row_time(0), timing_.row_time(timing_.height - 1));
  const double b = std::max(timing_.row_time(0), timing_.row_time(timing_.height - 1)) + meta.exposure_s;
  for (int k = 0; k < kKnots; ++k) {
    const double t = a + (b - a) * k / (kKnots - 1);
    VelocityEstimate e;
    if (velocity.at(meta.first_row_ns + static_cast<int64_t>(t * 1e9), e, horizon) != VelocityStatus::Ok) return false;
    out[k].t = t;
    for (int i = 0; i < 3; ++i) {
      out[k].w[i] = e.sample.w[i];
      out[k].v[i] = translate ? e.sample.v[i] : 0.0;
    }
  }
  return b > a;
}

RectifyResult FrameRectifier::process(const dsp::ImageView& src, const dsp::ImageView& dst, const drivers::FrameMeta& meta,
                                      const VelocityBuffer& velocity, uint64_t horizon) {
  RectifyResult r;
  r.reference_time_s = dsp::reference_time(timing_, cfg_.reference);
  if (!cfg_.enabled) {
    rect_->pass_through(src, dst);
    r.reason = "rectification disabled";
    return r;
  }
  // The samples covering the last row's exposure may still be on their way: wait for them, up
  // to the bound, and say when the motion beyond the newest one had to be held.
  const double end_s = std::max(timing_.row_time(0), timing_.row_time(timing_.height - 1)) + meta.exposure_s;
  wait_for_samples(meta.first_row_ns + static_cast<int64_t>(end_s * 1e9), velocity, horizon, r);
  // The velocity valid for this frame: at the middle of its readout.
  const int64_t t_mid = meta.first_row_ns + static_cast<int64_t>((0.5 * timing_.frame_readout_s() + 0.5 * meta.exposure_s) * 1e9);
  VelocityEstimate est;
  const VelocityStatus st = velocity.at(t_mid, est, horizon);
  if (st != VelocityStatus::Ok) {
    rect_->pass_through(src, dst);
    r.reason = st == VelocityStatus::NoData ? "no velocity received" : "velocity stale";
    return r;
  }
  // The camera's own motion (w, v) is the negated twist of the scene in its axes.
  const bool translate = est.sample.has_linear && !cfg_.gyro_only && cfg_.depth != DepthKind::Infinite;
  dsp::Twist tw;
  for (int i = 0; i < 3; ++i) {
    r.w[i] = est.sample.w[i];
    r.v[i] = translate ? est.sample.v[i] : 0.0;
    tw.w[i] = -r.w[i];
    tw.v[i] = -r.v[i];
  }
  r.velocity_age_s = est.age_s;
  const dsp::DepthModel depth = translate ? depth_model() : dsp::DepthModel::at_infinity();
  // Every row's orientation from the rates integrated up to its time; one rate held for the
  // frame only when the buffer cannot cover every row.
  dsp::IntegratedMotion::Knot k[kKnots];
  const dsp::RectifyReport rep = knots(meta, velocity, horizon, translate, k)
                                     ? rect_->rectify(src, dst, dsp::IntegratedMotion(k, kKnots), depth, r.reference_time_s)
                                     : rect_->rectify(src, dst, tw, depth, r.reference_time_s);
  r.rectified = rep.rectified;
  r.reason = rep.rectified    ? ""
             : rep.map_outside ? "the map puts most of the frame outside the captured image (camera model or motion out of reach)"
                               : "no rolling-shutter solution for this motion";
  // The correction this frame needed: the map's own largest displacement (at the reference time
  // the map was built for). The verdict checks the same reference on a coarse grid.
  r.max_correction_px = rep.rectified ? rep.max_displacement_px : 0.0;
  dsp::ApplicabilityOptions opt;
  opt.threshold_px = cfg_.threshold_px;
  opt.grid_cols = 5, opt.grid_rows = 4;  // corners, edges and centre: enough for a verdict per frame
  opt.reference = cfg_.reference == dsp::ReferenceRow::Middle ? dsp::CorrectionReference::MiddleRow
                                                              : dsp::CorrectionReference::FrameStart;
  const auto bound = dsp::correction_bound(cam_, timing_, tw, translate ? cfg_.depth_m : 1e6, opt);
  r.pinhole_sufficient = bound.pinhole_sufficient;
  return r;
}

}  // namespace rsd::daemon
