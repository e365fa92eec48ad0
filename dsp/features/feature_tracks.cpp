#include "dsp/features/feature_tracks.hpp"

#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rsd::dsp {

namespace {

// Strongest corners first (goodFeaturesToTrack sorts them), at most `per_cell` per bucket, so
// that texture-rich corners of the image do not take every match: rolling shutter shows
// across rows and distortion across the radius, so the matches must cover the frame.
std::vector<cv::Point2f> bucketed_corners(const cv::Mat& img, const TrackOptions& o) {
  std::vector<cv::Point2f> all;
  cv::goodFeaturesToTrack(img, all, 0, o.quality, o.min_distance_px);
  const int cells = o.grid_cols * o.grid_rows;
  const int per_cell = std::max(1, (o.max_per_pair + cells - 1) / cells);
  std::vector<int> count(cells, 0);
  std::vector<cv::Point2f> kept;
  for (const cv::Point2f& p : all) {
    const int cx = std::clamp(static_cast<int>(p.x * o.grid_cols / img.cols), 0, o.grid_cols - 1);
    const int cy = std::clamp(static_cast<int>(p.y * o.grid_rows / img.rows), 0, o.grid_rows - 1);
    if (count[cy * o.grid_cols + cx]++ < per_cell) kept.push_back(p);
  }
  return kept;
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

PairTracks track_pair(const cv::Mat& a, const cv::Mat& b, const TrackOptions& o) {
  if (a.type() != CV_8UC1 || b.type() != CV_8UC1 || a.size() != b.size() || a.empty())
    throw std::invalid_argument("track_pair: frames must be non-empty 8-bit grey images of one size");
  if (o.grid_cols < 1 || o.grid_rows < 1 || o.max_per_pair < 1 || o.window_px < 3)
    throw std::invalid_argument("track_pair: grid, cap and window must be positive");
  PairTracks out;
  const std::vector<cv::Point2f> pa = bucketed_corners(a, o);
  out.detected = static_cast<int>(pa.size());
  if (pa.empty()) return out;
  const cv::Size win(o.window_px, o.window_px);
  // Tight convergence: the matches feed a sub-pixel model fit (~0.1 px matters).
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 40, 0.001);
  std::vector<cv::Point2f> pb, back;
  std::vector<uchar> st_f, st_b;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(a, b, pa, pb, st_f, err, win, o.pyramid_levels, crit);
  cv::calcOpticalFlowPyrLK(b, a, pb, back, st_b, err, win, o.pyramid_levels, crit);
  for (size_t i = 0; i < pa.size() && static_cast<int>(out.a.size()) < o.max_per_pair; ++i) {
    if (!st_f[i] || !st_b[i] || !inside(pb[i], b, o.border_px) || !inside(pa[i], a, o.border_px)) {
      ++out.lost;
      continue;
    }
    const cv::Point2f d = back[i] - pa[i];
    if (d.dot(d) > o.max_fb_error_px * o.max_fb_error_px) {
      ++out.fb_rejected;
      continue;
    }
    if (ncc(a, pa[i], b, pb[i], o.window_px) < o.min_ncc) {
      ++out.ncc_rejected;
      continue;
    }
    out.a.emplace_back(pa[i].x, pa[i].y);
    out.b.emplace_back(pb[i].x, pb[i].y);
  }
  return out;
}

}  // namespace rsd::dsp
