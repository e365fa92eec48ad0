#include "dsp/diagnosis/remainder.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>

#include "dsp/core/statistics.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/instrument.hpp"
#include "dsp/diagnosis/observation_choice.hpp"
#include "dsp/diagnosis/parallax.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/diagnosis/stabiliser.hpp"

namespace rsd::dsp {

namespace {

constexpr double kClearZ = 4.0;           // "statistically clear"
constexpr double kMaterialShare = 0.2;    // structured variance over the noise variance
constexpr int kMaxPerFrame = 200;         // nearest neighbours are searched among these
constexpr size_t kMaxObservations = 20000;  // the remainder is assessed on at most these
constexpr int kMinLostTest = 8;             // observations a frame needs for the whole-frames test
constexpr double kLostMaterialShare = 0.05;  // of the tested observations, in lost frames

// One frame's inlier observations: their predicted pixels and their residuals.
struct Frame {
  int rank;
  std::vector<Eigen::Vector2d> px, r;
  Eigen::Vector2d mean() const {
    Eigen::Vector2d s = Eigen::Vector2d::Zero();
    for (const auto& x : r) s += x;
    return s / static_cast<double>(r.size());
  }
};

std::vector<Frame> frames_of(const DiagnosisModel& m, const std::vector<int>& idx,
                             const std::vector<Eigen::Vector2d>& r, const std::vector<bool>& in) {
  std::map<int, Frame> by_rank;
  for (size_t k = 0; k < idx.size(); ++k) {
    if (!in[k]) continue;
    Frame& f = by_rank[m.frame_rank(idx[k])];
    f.rank = m.frame_rank(idx[k]);
    // Where the model puts it: neighbours chosen by the observed (noisy) pixels would favour,
    // among a grid's equidistant neighbours, the one whose noise differs most.
    f.px.push_back(m.observed(idx[k]) - r[k]), f.r.push_back(r[k]);
  }
  std::vector<Frame> out;
  for (auto& [rank, f] : by_rank) {
    if (f.r.size() < 3) continue;
    // A frame with many observations keeps an even spread of them (features come in the
    // order they were detected, often row by row).
    if (f.r.size() > static_cast<size_t>(kMaxPerFrame)) {
      Frame kept{f.rank, {}, {}};
      for (size_t j = 0; j < static_cast<size_t>(kMaxPerFrame); ++j) {
        const size_t at = j * f.r.size() / kMaxPerFrame;
        kept.px.push_back(f.px[at]), kept.r.push_back(f.r[at]);
      }
      f = std::move(kept);
    }
    out.push_back(std::move(f));
  }
  return out;
}

// At most kMaxObservations of idx. The tests compare each observation with its neighbours in its
// frame and each frame's mean with the next frame's, so a frame needs several: an even share of
// the observations keeps every frame while that leaves each eight or more (up to 2 500 frames,
// about 80 s at 30 fps); past that it left ten minutes of a walk one or two a frame, too few to
// compare (a residual three times the noise was called noise), and whole runs of kMatchesRunFrames
// consecutive frames are taken instead, evenly over the recording, 16 observations of each.
std::vector<int> assessed_observations(const DiagnosisModel& m, const std::vector<int>& idx) {
  constexpr size_t kMinPerFrame = 8, kPerFrame = 16, kRun = kMatchesRunFrames;
  if (idx.size() <= kMaxObservations) return idx;
  std::vector<int> ranks;
  for (int i : idx) ranks.push_back(m.frame_rank(i));
  std::sort(ranks.begin(), ranks.end());
  const auto frames = static_cast<size_t>(std::unique(ranks.begin(), ranks.end()) - ranks.begin());
  if (frames * kMinPerFrame <= kMaxObservations) return subsample(idx, kMaxObservations);
  return evenly_in_runs(m, idx, kMaxObservations / (kPerFrame * kRun), kRun, kPerFrame);
}

// The independent noise: differences between each observation and its nearest neighbour in
// the same frame at least kSharedWindowPx away, whose error is not its own (a smooth field
// beneath cancels), and differences with an observation anywhere in the frame (it does not);
// both per coordinate, and how many values each rests on.
struct Scatter {
  double neighbour_var = 0, within_var = 0;
  // The noise's RMS within the inlier bound over its robust scale, from the same differences:
  // 1 for Gaussian noise; a tracker's errors have tails (1.39 on rsd-sim's 1080p rendering).
  double tail = 1;
  int n = 0;
};

// The first observation from half the frame's list on past i that lies kSharedWindowPx or more
// from it (i if none does).
size_t partner(const Frame& f, size_t i) {
  const size_t n = f.r.size();
  for (size_t step = 0; step + 1 < n; ++step) {
    const size_t j = (i + n / 2 + step) % n;
    if (j != i && (f.px[j] - f.px[i]).squaredNorm() >= kSharedWindowPx * kSharedWindowPx) return j;
  }
  return i;
}

Scatter scatter(const std::vector<Frame>& frames) {
  std::vector<Eigen::Vector2d> diff, far;
  for (const Frame& f : frames) {
    for (size_t i = 0; i < f.r.size(); ++i) {
      size_t best = i;
      double best_d2 = std::numeric_limits<double>::infinity();
      for (size_t j = 0; j < f.r.size(); ++j) {
        const double d2 = (f.px[j] - f.px[i]).squaredNorm();
        if (d2 >= kSharedWindowPx * kSharedWindowPx && d2 < best_d2) best_d2 = d2, best = j;
      }
      if (best != i) diff.push_back(f.r[i] - f.r[best]);
      // Against an observation about half the frame's list away, anywhere in the image (the
      // field does not cancel) but not in its window, so that both sides are differences of two
      // independent errors: a heavy-tailed noise's difference has a larger robust scale than the
      // noise itself (on rsd-sim's rendering 0.058 against 0.049 px), and the scatter about the
      // frame mean, set against it, hid a field of up to a third of the noise variance.
      if (const size_t j = partner(f, i); j != i) far.push_back(f.r[i] - f.r[j]);
    }
  }
  Scatter s;
  s.n = static_cast<int>(diff.size());
  if (diff.empty()) return s;
  const RobustStats d = robust_stats(diff);
  const double nb = d.scale_px, w = robust_stats(far).scale_px;
  s.neighbour_var = 0.5 * nb * nb;  // a difference carries two observations' noise
  s.tail = nb > 0 ? d.rms_px / nb : 1.0;
  s.within_var = 0.5 * w * w;
  return s;
}

// The sequence of frame means, per coordinate: its variance, half its mean squared step, and
// the independent noise each mean carries on average.
struct MeanSeries {
  double var = 0, step = 0, own_noise = 0;
  int frames = 0;
};

MeanSeries mean_series(const std::vector<Frame>& frames, double noise_var) {
  MeanSeries s;
  s.frames = static_cast<int>(frames.size());
  if (s.frames < 3) return s;
  std::vector<Eigen::Vector2d> means;
  Eigen::Vector2d grand = Eigen::Vector2d::Zero();
  for (const Frame& f : frames) {
    means.push_back(f.mean());
    grand += means.back();
    s.own_noise += noise_var / static_cast<double>(f.r.size());
  }
  grand /= s.frames;
  s.own_noise /= s.frames;
  for (size_t k = 0; k < means.size(); ++k) {
    s.var += 0.5 * (means[k] - grand).squaredNorm();
    if (k > 0) s.step += 0.25 * (means[k] - means[k - 1]).squaredNorm();
  }
  s.var /= (s.frames - 1);
  s.step /= (s.frames - 1);
  return s;
}

// P(X > n / 2) for X ~ Binomial(n, p): a frame lost by chance, its mismatches independent.
double majority_tail(int n, double p) {
  if (p <= 0) return 0;
  if (p >= 1) return 1;
  double tail = 0;
  for (int k = n / 2 + 1; k <= n; ++k)
    tail += std::exp(std::lgamma(n + 1.0) - std::lgamma(k + 1.0) - std::lgamma(n - k + 1.0) + k * std::log(p) +
                     (n - k) * std::log1p(-p));
  return std::min(1.0, tail);
}

// The whole-frames test: frames most of whose observations are outliers, against the count
// that the outlier share of a typical frame (the median frame's, which frames lost whole do not
// move) gives by chance. One is added to the binomial variance: mismatches are not quite
// independent (a repeated texture mismatches together), and a frame or two the binomial calls
// nearly impossible is not clear physics.
void test_whole_frames(const DiagnosisModel& m, const std::vector<int>& idx, const std::vector<bool>& in, Remainder& r) {
  std::map<int, std::pair<int, int>> per;  // frame rank -> (outliers, observations)
  for (size_t k = 0; k < idx.size(); ++k) {
    auto& c = per[m.frame_rank(idx[k])];
    c.first += in[k] ? 0 : 1, c.second += 1;
  }
  std::vector<double> shares;
  for (const auto& [rank, c] : per)
    if (c.second >= kMinLostTest) shares.push_back(static_cast<double>(c.first) / c.second);
  if (shares.size() < 3) return;
  const double p = median(shares);
  double variance = 1, tested = 0, in_lost = 0;
  for (const auto& [rank, c] : per) {
    if (c.second < kMinLostTest) continue;
    const double q = majority_tail(c.second, p);
    r.lost_expected += q, variance += q * (1 - q), tested += c.second, ++r.tested_frames;
    if (2 * c.first > c.second) ++r.lost_frames, in_lost += c.second;
  }
  r.lost_z = (r.lost_frames - r.lost_expected) / std::sqrt(variance);
  r.lost_share = in_lost / tested;
  r.lost = r.lost_z > kClearZ && r.lost_share >= kLostMaterialShare;
}

std::string percent(double share) { return std::to_string(std::lround(100 * share)) + "%"; }

std::string summary_of(const Remainder& r) {
  std::ostringstream o;
  o.precision(3);
  if (r.nothing_to_explain) o << "The nominal model fits within noise. ";
  else o << "The named effects explain " << percent(r.explained_share) << " of the mismatch beyond noise. ";
  o << "The final residual is " << r.rms_px << " px per coordinate, where noise alone leaves " << r.expected_rms_px
    << " px";
  if (r.stated_noise_px > 0) o << " (the recording states " << r.stated_noise_px << " px)";
  o << ". ";
  if (!r.significant && r.instrument_px > 0) {
    o << "What remains holds " << r.instrument_px << " px of structure, under the " << kInstrumentBiasPx
      << " px a tracker's or a target detector's own bias reaches: the instrument's as much as the scene's, not "
         "physics to tell from it; the rest is noise.";
    return o.str();
  }
  if (!r.significant) {
    o << "What remains has no structure in the image or in time: it is noise.";
    return o.str();
  }
  if (r.stabilised)
    o << "The pictures follow the gyro smoothed over " << std::lround(1e3 * r.stabiliser_sigma_s)
      << " ms (a Gaussian's sigma), not the gyro itself: a video stabilised in the camera (electronic or optical "
         "stabilisation), whose gain falls with the motion's frequency where a gyro scale's or a focal length's is "
         "one at every frequency. Record with the stabilisation off to calibrate. ";
  if (r.offset_beside_stabiliser)
    o << "The clock offset named beside it may be the stabiliser's delay rather than the clocks' (a stabiliser "
         "that does not look ahead lags the motion): measure it with the stabilisation off. ";
  o << "What remains is not noise";
  if (r.spatial || r.temporal || r.lost) o << ":";
  if (r.spatial) o << " " << r.spatial_rms_px << " px vary smoothly across each frame";
  if (r.spatial && r.temporal) o << ", and";
  if (r.temporal) o << " " << r.temporal_rms_px << " px move all of a frame's observations together, smoothly from frame to frame";
  if (r.lost && (r.spatial || r.temporal)) o << ", and";
  if (r.lost)
    o << " " << r.lost_frames << " of " << r.tested_frames << " frames (" << percent(r.lost_share)
      << " of the observations) are mostly outliers, where mismatches alone would make " << r.lost_expected
      << ": whole frames the model does not predict";
  o << ". No effect of the table explains it";
  if (!r.located.empty()) o << "; it lives mostly in " << r.located.front().signal << " (" << r.located.front().detail << ")";
  o << ".";
  return o.str();
}

// Where the remainder lives: the baseline's signals on the final residual, the two tests'
// structured parts as shares of the residual energy, and the parallax pattern for matches.
std::vector<Located> locate_remainder(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx,
                                      const Remainder& r) {
  std::vector<Located> out = locate(m, p, idx);
  const double total = r.rms_px * r.rms_px;
  if (r.stabilised) {
    // The share of the residual energy the smoothing takes away.
    const DiagnosisModel smoothed(m, smoothed_rates(m.gyro_samples(), r.stabiliser_sigma_s));
    const double left = robust_stats(smoothed.residuals(p, idx)).rms_px;
    out.push_back({"stabilisation", std::clamp(1 - left * left / total, 0.0, 1.0),
                   "the pictures follow the gyro smoothed over time, not the gyro itself: a video stabilised in the "
                   "camera, which the rotation model of matches cannot express"});
  }
  if (r.temporal)
    out.push_back({"frame_shift", std::min(1.0, r.temporal_rms_px * r.temporal_rms_px / total),
                   "all of a frame's observations are displaced together, and the displacement changes smoothly "
                   "from frame to frame: motion the motion data do not carry, or a clock error that changes"});
  if (r.lost)
    out.push_back({"lost_frames", r.lost_share,
                   "whole frames whose observations the model does not predict (most of them outliers): motion the "
                   "motion data do not carry in those frames (a gyro that clips, a clock that skips)"});
  if (r.spatial)
    out.push_back({"image_field", std::min(1.0, r.spatial_rms_px * r.spatial_rms_px / total),
                   "neighbouring observations of a frame share their residual: a smooth field across the image"});
  if (m.kind() == ObservationKind::Matches) {
    const Parallax px = parallax_signal(m, p, idx);
    if (px.clear())
      out.push_back({"translation", px.share,
                     "each frame pair's residual is the flow of a camera translation, not of a rotation: parallax "
                     "of a near scene, which the rotation-only model of matches cannot express"});
  }
  std::sort(out.begin(), out.end(), [](const Located& a, const Located& b) { return a.strength > b.strength; });
  // frame_shift, image_field and lost_frames say how the remainder is structured, the others what it
  // follows (a span of time, the fast frames, a translation, ...): one of those first when it
  // explains a fifth of it (a gyro that clips shifts its fast frames, a clock that jumps every
  // frame after the jump).
  std::stable_partition(out.begin(), out.end(), [](const Located& l) {
    return l.strength >= 0.2 && l.signal != "frame_shift" && l.signal != "image_field" && l.signal != "lost_frames";
  });
  // A stabiliser, found by the selection against the gains that stood in for it, first.
  std::stable_partition(out.begin(), out.end(), [](const Located& l) { return l.signal == "stabilisation"; });
  return out;
}

}  // namespace

Remainder assess_remainder(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx_all,
                           double noise_floor_px, double baseline_rms_px, std::optional<double> stabiliser_sigma_s,
                           bool offset_named) {
  Remainder r;
  ModelParams fitted = p;
  fitted.translation_nuisance = false;  // the residual the model leaves, parallax and all
  const std::vector<int> idx = assessed_observations(m, idx_all);
  const auto res = m.residuals(fitted, idx);
  r.rms_px = robust_stats(res).rms_px;
  r.stated_noise_px = noise_floor_px;
  const std::vector<bool> in = inliers(res);
  const std::vector<Frame> frames = frames_of(m, idx, res, in);
  const Scatter sc = scatter(frames);
  if (sc.n < 20 || !(sc.neighbour_var > 0)) {
    r.expected_rms_px = noise_floor_px > 0 ? noise_floor_px : r.rms_px;
    r.summary = "Too few observations per frame to test the remainder for structure.";
    return r;
  }
  const double noise_var = sc.neighbour_var;
  // Material against the noise's variance in the residual's own units (its RMS, tails and all:
  // "a residual 10-15% above the expected noise" is in RMS). A tracker's errors carry a field of
  // their own, 0.024 px on rsd-sim's rendering under 0.066 px of noise (0.052 px of robust scale),
  // a seventh of its variance: noise, as the nominal model fits within it.
  // And at least the instrument's own bias (instrument.hpp): an independent renderer's pictures,
  // tracked to 0.042 px, left a field of 0.023 px, over a fifth of that noise's variance.
  const double share_var = kMaterialShare * noise_var * sc.tail * sc.tail;
  const double material_var = std::max(share_var, kInstrumentBiasPx * kInstrumentBiasPx);
  // Clear and a share of the noise, but under the instrument's bias: said, not called physics.
  const auto under_instrument = [&](double z, double var) {
    if (z > kClearZ && var > share_var && var <= material_var) r.instrument_px = std::max(r.instrument_px, std::sqrt(var));
  };
  // Spatial: log of the variance ratio, its standard error inflated by half for the sharing
  // of observations between neighbour pairs.
  r.spatial_ratio = sc.within_var / noise_var;
  r.spatial_z = std::log(r.spatial_ratio) / (1.5 * std::sqrt(2.0 / sc.n));
  r.spatial = r.spatial_z > kClearZ && sc.within_var - noise_var > material_var;
  r.spatial_rms_px = r.spatial ? std::sqrt(sc.within_var - noise_var) : 0;
  under_instrument(r.spatial_z, sc.within_var - noise_var);
  // Temporal: the von Neumann ratio over both coordinates has standard error 1/sqrt(2F).
  const MeanSeries ms = mean_series(frames, noise_var);
  double frame_white = 0;  // variance of the frame-common errors that are independent per frame
  if (ms.frames >= 3 && ms.var > 0) {
    r.temporal_ratio = ms.step / ms.var;
    r.temporal_z = (1 - r.temporal_ratio) * std::sqrt(2.0 * ms.frames);
    const double smooth = std::max(0.0, ms.var - ms.step);
    r.temporal = r.temporal_z > kClearZ && smooth > material_var;
    r.temporal_rms_px = r.temporal ? std::sqrt(smooth) : 0;
    under_instrument(r.temporal_z, smooth);
    frame_white = std::max(0.0, std::min(ms.var, ms.step) - ms.own_noise);
  }
  // In the units of rms_px (the inliers' RMS, tails and all), so that the two compare: a
  // tracker's heavy-tailed noise alone left 0.068 px against a scale of 0.052 px, and the report
  // said a quarter of the residual was mismatch beyond noise while calling it noise.
  r.expected_rms_px = std::sqrt(noise_var * sc.tail * sc.tail + frame_white);
  test_whole_frames(m, idx, in, r);
  r.stabilised = stabiliser_sigma_s.has_value();
  r.stabiliser_sigma_s = stabiliser_sigma_s.value_or(0);
  r.offset_beside_stabiliser = r.stabilised && offset_named;
  r.significant = r.spatial || r.temporal || r.lost || r.stabilised;
  // The nominal model within 5% of the noise left nothing to explain.
  r.nothing_to_explain = baseline_rms_px <= 1.05 * r.expected_rms_px;
  const double excess = baseline_rms_px * baseline_rms_px - r.expected_rms_px * r.expected_rms_px;
  r.explained_share = r.nothing_to_explain
                          ? 1.0
                          : std::clamp((baseline_rms_px * baseline_rms_px - r.rms_px * r.rms_px) / excess, 0.0, 1.0);
  if (r.significant) r.located = locate_remainder(m, fitted, idx, r);
  r.summary = summary_of(r);
  return r;
}

}  // namespace rsd::dsp
