#include "dsp/features/feature_tracks.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

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

// What LK's window about p holds, from the gradient g at each of its pixels (G = g g^T, M the
// sum of G over the window, o a pixel's offset from p):
// - ratio: M's smaller eigenvalue over its larger; near 0 where the window holds one straight
//   edge, along which LK's position is free;
// - turn_offset: how far from p lies the point LK's translation follows when the window turns in
//   the image. A turn by theta moves each offset by theta J o (J the quarter turn), and LK's least
//   squares then moves its estimate by -theta M^-1 sum G J o: by theta J d, d = -J M^-1 sum G J o,
//   as if the window turned about p + d. Zero for a structure centred on p (an X-corner's saddle,
//   a blob); half a window where p sits on an edge ending in a corner at the window's rim, which
//   LK follows.
struct WindowShape {
  double ratio = 0, turn_offset = std::numeric_limits<double>::infinity();
};
WindowShape window_shape(const cv::Mat& img, const cv::Point2f& p, int win) {
  cv::Mat A, gx, gy;
  cv::getRectSubPix(img, cv::Size(win + 2, win + 2), p, A, CV_32F);
  cv::Sobel(A, gx, CV_32F, 1, 0, 3);
  cv::Sobel(A, gy, CV_32F, 0, 1, 3);
  Eigen::Matrix2d M = Eigen::Matrix2d::Zero();
  Eigen::Vector2d v = Eigen::Vector2d::Zero();
  const double half = 0.5 * (win - 1);
  for (int y = 0; y < win; ++y)
    for (int x = 0; x < win; ++x) {
      const Eigen::Vector2d g(gx.at<float>(y + 1, x + 1), gy.at<float>(y + 1, x + 1));
      const Eigen::Matrix2d G = g * g.transpose();
      M += G;
      v += G * Eigen::Vector2d(-(y - half), x - half);  // G J o
    }
  WindowShape w;
  const double tr = M.trace(), det = M.determinant();
  if (!(tr > 0 && det > 0)) return w;
  const double dev = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
  w.ratio = (0.5 * tr - dev) / (0.5 * tr + dev);
  w.turn_offset = M.ldlt().solve(v).norm();  // |J M^-1 v| = |M^-1 v|
  if (!std::isfinite(w.turn_offset)) w.turn_offset = std::numeric_limits<double>::infinity();
  return w;
}

}  // namespace

FeatureTracker::FeatureTracker(const TrackOptions& o) : o_(o) {
  if (o.grid_cols < 1 || o.grid_rows < 1 || o.max_per_pair < 1 || o.window_px < 3 || o.pyramid_levels < 0 || o.max_iterations < 1 ||
      o.detect_level < 0 || o.detect_level > o.pyramid_levels)
    throw std::invalid_argument("feature tracker: grid, cap and window must be positive");
  if (!(o.min_corner_ratio >= 0 && o.min_corner_ratio <= 1))
    throw std::invalid_argument("feature tracker: min_corner_ratio must lie in [0, 1] (the structure tensor's eigenvalue ratio)");
  if (!(o.max_turn_offset > 0))
    throw std::invalid_argument("feature tracker: max_turn_offset must be positive (a share of the window; infinite: off)");
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
    int& in_cell = count[cell_of(p, size, o_)];
    if (in_cell >= per_cell) continue;
    const WindowShape w = window_shape(pyr[0], p, o_.window_px);
    if (w.ratio < o_.min_corner_ratio || w.turn_offset > o_.max_turn_offset * o_.window_px) continue;
    ++in_cell;
    kept.push_back(p);
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
