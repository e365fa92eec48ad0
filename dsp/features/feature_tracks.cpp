#include "dsp/features/feature_tracks.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rsd::dsp {

namespace {

int cell_of(const cv::Point2f& p, const cv::Size& size, const TrackOptions& o) {
  const int cx = std::clamp(static_cast<int>(p.x * o.grid_cols / size.width), 0, o.grid_cols - 1);
  const int cy = std::clamp(static_cast<int>(p.y * o.grid_rows / size.height), 0, o.grid_rows - 1);
  return cy * o.grid_cols + cx;
}

bool inside(const cv::Point2f& p, const cv::Mat& img, int border) {
  return p.x >= border && p.y >= border && p.x <= img.cols - 1 - border && p.y <= img.rows - 1 - border;
}

// Zero-mean normalised cross-correlation of the sub-pixel patches centred on pa and pb.
double ncc(const cv::Mat& a, const cv::Point2f& pa, const cv::Mat& b, const cv::Point2f& pb, int win) {
  cv::Mat A, B;
  cv::getRectSubPix(a, cv::Size(win, win), pa, A, CV_32F);
  cv::getRectSubPix(b, cv::Size(win, win), pb, B, CV_32F);
  A -= cv::mean(A)[0];
  B -= cv::mean(B)[0];
  const double den = std::sqrt(A.dot(A) * B.dot(B));
  return den > 0 ? A.dot(B) / den : 0.0;
}

}  // namespace

FeatureTracker::FeatureTracker(const TrackOptions& o) : o_(o) {
  if (o.grid_cols < 1 || o.grid_rows < 1 || o.max_per_pair < 1 || o.window_px < 3 || o.pyramid_levels < 0 || o.max_iterations < 1 ||
      o.detect_level < 0 || o.detect_level > o.pyramid_levels)
    throw std::invalid_argument("feature tracker: grid, cap and window must be positive");
}

void FeatureTracker::restart() {
  prev_.clear();
  carried_.clear();
}

// `have` first, then the strongest new corners (goodFeaturesToTrack sorts them) at least
// min_distance_px from them, at most max_per_pair / cells per bucket in all, so that
// texture-rich corners of the image do not take every match: rolling shutter shows across rows
// and distortion across the radius, so the matches must cover the frame.
std::vector<cv::Point2f> FeatureTracker::corners(const std::vector<cv::Mat>& pyr, const std::vector<cv::Point2f>& have) const {
  const cv::Size size = pyr[0].size();
  const int cells = o_.grid_cols * o_.grid_rows;
  const int per_cell = std::max(1, (o_.max_per_pair + cells - 1) / cells);
  std::vector<int> count(cells, 0);
  for (const cv::Point2f& p : have) ++count[cell_of(p, size, o_)];
  // The pyramid holds each level's image and its derivatives, two entries a level.
  const int level = std::min(o_.detect_level, static_cast<int>(pyr.size() / 2) - 1);
  const cv::Mat& img = pyr[2 * static_cast<size_t>(level)];
  const float scale = static_cast<float>(1 << level), shift = 0.5f * (scale - 1);  // pixel centres
  cv::Mat mask;
  if (!have.empty()) {
    mask = cv::Mat(img.size(), CV_8UC1, cv::Scalar(255));
    const int r = static_cast<int>(std::ceil(o_.min_distance_px / scale));
    for (const cv::Point2f& p : have)
      cv::circle(mask, cv::Point(cvRound((p.x - shift) / scale), cvRound((p.y - shift) / scale)), r, cv::Scalar(0), cv::FILLED);
  }
  std::vector<cv::Point2f> all;
  cv::goodFeaturesToTrack(img, all, 0, o_.quality, o_.min_distance_px / scale, mask);
  std::vector<cv::Point2f> kept = have;
  for (cv::Point2f p : all) {
    p = p * scale + cv::Point2f(shift, shift);
    if (count[cell_of(p, size, o_)]++ < per_cell) kept.push_back(p);
  }
  return kept;
}

PairTracks FeatureTracker::next(const cv::Mat& frame) {
  if (frame.type() != CV_8UC1 || frame.empty())
    throw std::invalid_argument("feature tracker: a frame must be a non-empty 8-bit grey image");
  if (!prev_.empty() && frame.size() != prev_[0].size())
    throw std::invalid_argument("feature tracker: a frame of " + std::to_string(frame.cols) + "x" + std::to_string(frame.rows) +
                                " in a chain of " + std::to_string(prev_[0].cols) + "x" + std::to_string(prev_[0].rows));
  const cv::Size win(o_.window_px, o_.window_px);
  // Copied (tryReuseInputImage false): the caller's buffer may be reused once this returns.
  cv::buildOpticalFlowPyramid(frame, cur_, win, o_.pyramid_levels, true, cv::BORDER_REFLECT_101, cv::BORDER_CONSTANT, false);
  PairTracks out;
  if (prev_.empty()) {
    carried_ = o_.carry ? corners(cur_, {}) : std::vector<cv::Point2f>{};
    std::swap(prev_, cur_);
    return out;
  }
  const cv::Mat& a = prev_[0];
  const cv::Mat& b = cur_[0];
  const std::vector<cv::Point2f> pa = o_.carry ? carried_ : corners(prev_, {});
  out.detected = static_cast<int>(pa.size());
  std::vector<cv::Point2f> kept;
  if (!pa.empty()) {
    // Tight convergence: the matches feed a sub-pixel model fit (~0.1 px matters).
    const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, o_.max_iterations, 0.001);
    std::vector<cv::Point2f> pb, back;
    std::vector<uchar> st_f, st_b;
    std::vector<float> err;
    cv::calcOpticalFlowPyrLK(prev_, cur_, pa, pb, st_f, err, win, o_.pyramid_levels, crit);
    cv::calcOpticalFlowPyrLK(cur_, prev_, pb, back, st_b, err, win, o_.pyramid_levels, crit);
    for (size_t i = 0; i < pa.size() && static_cast<int>(out.a.size()) < o_.max_per_pair; ++i) {
      if (!st_f[i] || !st_b[i] || !inside(pb[i], b, o_.border_px) || !inside(pa[i], a, o_.border_px)) {
        ++out.lost;
        continue;
      }
      const cv::Point2f d = back[i] - pa[i];
      if (d.dot(d) > o_.max_fb_error_px * o_.max_fb_error_px) {
        ++out.fb_rejected;
        continue;
      }
      if (ncc(a, pa[i], b, pb[i], o_.window_px) < o_.min_ncc) {
        ++out.ncc_rejected;
        continue;
      }
      out.a.emplace_back(pa[i].x, pa[i].y);
      out.b.emplace_back(pb[i].x, pb[i].y);
      kept.push_back(pb[i]);
    }
  }
  if (o_.carry)
    carried_ = kept.size() < o_.refill_below * o_.max_per_pair ? corners(cur_, kept) : std::move(kept);
  std::swap(prev_, cur_);
  return out;
}

// The tracker's own checks name a bad frame (type, emptiness, a size other than a's).
PairTracks track_pair(const cv::Mat& a, const cv::Mat& b, const TrackOptions& o) {
  TrackOptions fresh = o;
  fresh.carry = false;
  FeatureTracker t(fresh);
  t.next(a);
  return t.next(b);
}

}  // namespace rsd::dsp
