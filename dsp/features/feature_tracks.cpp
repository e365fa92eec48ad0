#include "dsp/features/feature_tracks.hpp"

#include <opencv2/calib3d.hpp>
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

// The structure tensor summed over LK's window about p (the gradient's outer product at each of
// its pixels): its smaller eigenvalue over its larger, near 0 where the window holds one straight
// edge, along which LK's position is free.
double corner_ratio(const cv::Mat& img, const cv::Point2f& p, int win) {
  cv::Mat A, gx, gy;
  cv::getRectSubPix(img, cv::Size(win + 2, win + 2), p, A, CV_32F);
  cv::Sobel(A, gx, CV_32F, 1, 0, 3);
  cv::Sobel(A, gy, CV_32F, 0, 1, 3);
  const cv::Rect in(1, 1, win, win);
  const double xx = gx(in).dot(gx(in)), yy = gy(in).dot(gy(in)), xy = gx(in).dot(gy(in));
  const double tr = xx + yy, det = xx * yy - xy * xy;
  if (!(tr > 0 && det > 0)) return 0;
  const double dev = std::sqrt(std::max(0.0, 0.25 * tr * tr - det));
  return (0.5 * tr - dev) / (0.5 * tr + dev);
}

// p through the homography h (3x3, double).
cv::Point2f mapped(const cv::Mat& h, const cv::Point2f& p) {
  const cv::Vec3d q = cv::Matx33d(h) * cv::Vec3d(p.x, p.y, 1);
  return {static_cast<float>(q[0] / q[2]), static_cast<float>(q[1] / q[2])};
}

}  // namespace

FeatureTracker::FeatureTracker(const TrackOptions& o) : o_(o) {
  if (o.grid_cols < 1 || o.grid_rows < 1 || o.max_per_pair < 1 || o.window_px < 3 || o.pyramid_levels < 0 || o.max_iterations < 1 ||
      o.detect_level < 0 || o.detect_level > o.pyramid_levels)
    throw std::invalid_argument("feature tracker: grid, cap and window must be positive");
  if (!(o.min_corner_ratio >= 0 && o.min_corner_ratio <= 1))
    throw std::invalid_argument("feature tracker: min_corner_ratio must lie in [0, 1] (the structure tensor's eigenvalue ratio)");
  if (!(o.align_above_px >= 0))
    throw std::invalid_argument("feature tracker: align_above_px must be at least 0 (pixels; infinite: never)");
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
    if (corner_ratio(pyr[0], p, o_.window_px) < o_.min_corner_ratio) continue;
    ++in_cell;
    kept.push_back(p);
  }
  return kept;
}

// How the second picture is turned, zoomed and tilted against the first: the homography H
// (first picture's pixels to the second's) fitted robustly to a coarse tracking of at most 64 of
// the corners, when it moves the picture's corners by align_above_px or more beyond the shift of
// its centre; none where too few corners track or most do not agree on one H. The coarse tracking needs no precision: H only
// has to leave LK's windows a turn small enough to neglect.
std::optional<cv::Mat> FeatureTracker::turn_between(const std::vector<cv::Point2f>& pa) const {
  constexpr size_t kCoarse = 64;
  constexpr int kEnough = 12;
  if (pa.size() < kEnough) return std::nullopt;
  std::vector<cv::Point2f> from, to;
  const size_t stride = std::max<size_t>(1, pa.size() / kCoarse);
  for (size_t i = 0; i < pa.size(); i += stride) from.push_back(pa[i]);
  std::vector<uchar> st;
  std::vector<float> err;
  const cv::TermCriteria coarse(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, o_.max_iterations, 0.01);
  const cv::Size win(o_.window_px, o_.window_px);
  cv::calcOpticalFlowPyrLK(prev_, cur_, from, to, st, err, win, o_.pyramid_levels, coarse);
  std::vector<cv::Point2f> f, t;
  for (size_t i = 0; i < from.size(); ++i)
    if (st[i]) f.push_back(from[i]), t.push_back(to[i]);
  if (f.size() < kEnough) return std::nullopt;
  std::vector<uchar> inliers;
  cv::Mat h = cv::findHomography(f, t, cv::RANSAC, 1.0, inliers);
  // Where most of the corners do not move as one picture (a near scene's parallax, something
  // moving across the view), no homography says how the windows turn: they are tracked as they are.
  const int agree = h.empty() ? 0 : cv::countNonZero(inliers);
  if (agree < kEnough || 2 * static_cast<size_t>(agree) < f.size()) return std::nullopt;
  const cv::Size size = prev_[0].size();
  const cv::Point2f centre(0.5f * (size.width - 1), 0.5f * (size.height - 1));
  const cv::Point2f shift = mapped(h, centre) - centre;
  double moved = 0;
  for (const cv::Point2f c : {cv::Point2f(0, 0), cv::Point2f(size.width - 1, 0), cv::Point2f(0, size.height - 1),
                              cv::Point2f(size.width - 1, size.height - 1)}) {
    const cv::Point2f d = mapped(h, c) - c - shift;
    moved = std::max(moved, static_cast<double>(std::hypot(d.x, d.y)));
  }
  // A picture turned by a quarter of its size is no frame pair LK follows; such an H is wrong.
  if (!(moved >= o_.align_above_px && moved < 0.25 * std::max(size.width, size.height))) return std::nullopt;
  // LK follows a shift without error: H's is kept to whole pixels at the picture's centre, so that
  // there the picture is not resampled (interpolation adds to the matches' noise).
  const cv::Matx33d whole(1, 0, std::round(shift.x) - shift.x, 0, 1, std::round(shift.y) - shift.y, 0, 0, 1);
  return cv::Mat(whole * cv::Matx33d(h));
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
  // Tracked into the second picture as it is, or into it turned back onto the first
  // (align_above_px): the turned picture shows at q what the second shows at H q.
  const std::optional<cv::Mat> turn = std::isinf(o_.align_above_px) ? std::nullopt : turn_between(pa);
  if (turn) {
    cv::warpPerspective(b, aligned_image_, *turn, b.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
    cv::buildOpticalFlowPyramid(aligned_image_, aligned_, win, o_.pyramid_levels, true, cv::BORDER_REFLECT_101,
                                cv::BORDER_CONSTANT, false);
  }
  const std::vector<cv::Mat>& second = turn ? aligned_ : cur_;
  const cv::Mat& b2 = second[0];
  std::vector<cv::Point2f> kept;
  if (!pa.empty()) {
    // Tight convergence: the matches feed a sub-pixel model fit (~0.1 px matters).
    const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, o_.max_iterations, 0.001);
    std::vector<cv::Point2f> pb, back;
    std::vector<uchar> st_f, st_b;
    std::vector<float> err;
    cv::calcOpticalFlowPyrLK(prev_, second, pa, pb, st_f, err, win, o_.pyramid_levels, crit);
    cv::calcOpticalFlowPyrLK(second, prev_, pb, back, st_b, err, win, o_.pyramid_levels, crit);
    for (size_t i = 0; i < pa.size() && static_cast<int>(out.a.size()) < o_.max_per_pair; ++i) {
      const cv::Point2f in_b = turn ? mapped(*turn, pb[i]) : pb[i];
      if (!st_f[i] || !st_b[i] || !inside(in_b, b, o_.border_px) || !inside(pb[i], b2, o_.border_px) ||
          !inside(pa[i], a, o_.border_px)) {
        ++out.lost;
        continue;
      }
      const cv::Point2f d = back[i] - pa[i];
      if (d.dot(d) > o_.max_fb_error_px * o_.max_fb_error_px) {
        ++out.fb_rejected;
        continue;
      }
      if (ncc(a, pa[i], b2, pb[i], o_.window_px) < o_.min_ncc) {
        ++out.ncc_rejected;
        continue;
      }
      out.a.emplace_back(pa[i].x, pa[i].y);
      out.b.emplace_back(in_b.x, in_b.y);
      kept.push_back(in_b);
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
