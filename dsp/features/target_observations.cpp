#include "dsp/features/target_observations.hpp"

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <sstream>
#include <stdexcept>


namespace rsd::dsp {

namespace {

std::vector<CornerObservation> detect_checkerboard(const cv::Mat& grey, const TargetSpec& spec) {
  std::vector<cv::Point2f> c;
  // The sector-based detector is sub-pixel by itself; ACCURACY upsamples for the final
  // refinement. Measured on rendered boards (tests/dsp/features/test_extract.cpp): RMS 0.03-0.04 px, mean
  // bias 0.005-0.03 px depending on the view. cornerSubPix afterwards was worse (RMS up to
  // 0.14 px, bias up to 0.04 px on an axis-aligned board), so it is not used.
  if (!cv::findChessboardCornersSB(grey, cv::Size(spec.cols, spec.rows), c, cv::CALIB_CB_ACCURACY)) return {};
  if (c.size() != static_cast<size_t>(spec.rows * spec.cols)) return {};
  auto at = [&](int i, int j) -> cv::Point2f& { return c[i * spec.cols + j]; };
  // Handedness: along a row x must grow relative to down a column as the image's axes do;
  // a mirrored ordering is fixed by reversing each row.
  const cv::Point2f row = at(0, spec.cols - 1) - at(0, 0), col = at(spec.rows - 1, 0) - at(0, 0);
  if (row.x * col.y - row.y * col.x < 0)
    for (int i = 0; i < spec.rows; ++i) std::reverse(&at(i, 0), &at(i, 0) + spec.cols);
  // The 180-degree ambiguity: corner 0 is the one nearer the image's top-left.
  if (c.front().x + c.front().y > c.back().x + c.back().y) std::reverse(c.begin(), c.end());
  std::vector<CornerObservation> out;
  for (size_t k = 0; k < c.size(); ++k) out.push_back({static_cast<int>(k), Eigen::Vector2d(c[k].x, c[k].y)});
  return out;
}

std::vector<CornerObservation> detect_aprilgrid(const cv::Mat& grey, const TargetSpec& spec) {
  static const auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_APRILTAG_36h11);
  auto params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;  // measured 0.06 px (test_aprilgrid)
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int> ids;
  cv::aruco::detectMarkers(grey, dict, corners, ids, params);
  std::vector<CornerObservation> out;
  for (size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] < 0 || ids[i] >= spec.rows * spec.cols) continue;  // a tag of another target
    for (int k = 0; k < 4; ++k) out.push_back({4 * ids[i] + k, Eigen::Vector2d(corners[i][k].x, corners[i][k].y)});
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  // A tag id seen twice is a misdetection (or two targets): keep neither.
  std::vector<CornerObservation> unique;
  for (size_t i = 0; i < out.size(); ++i) {
    const bool dup = (i > 0 && out[i - 1].id == out[i].id) || (i + 1 < out.size() && out[i + 1].id == out[i].id);
    if (!dup) unique.push_back(out[i]);
  }
  return unique;
}

}  // namespace

std::vector<dsp::Landmark> target_points(const TargetSpec& s) {
  std::vector<dsp::Landmark> pts;
  if (s.kind == TargetKind::Checkerboard) {
    for (int i = 0; i < s.rows; ++i)
      for (int j = 0; j < s.cols; ++j)
        pts.push_back({i * s.cols + j, Eigen::Vector3d((j - 0.5 * (s.cols - 1)) * s.spacing_m,
                                                       (i - 0.5 * (s.rows - 1)) * s.spacing_m, 0.0)});
    return pts;
  }
  if (s.kind != TargetKind::AprilGrid) throw std::invalid_argument("target_points: checkerboard or aprilgrid only");
  const double tag = s.spacing_m, gap = s.tag_spacing * tag;
  const double w = s.cols * tag + (s.cols + 1) * gap, h = s.rows * tag + (s.rows + 1) * gap;
  const Eigen::Vector2d offsets[4] = {{0, 0}, {tag, 0}, {tag, tag}, {0, tag}};
  for (int r = 0; r < s.rows; ++r)
    for (int c = 0; c < s.cols; ++c) {
      const Eigen::Vector2d tl(gap + c * (tag + gap) - 0.5 * w, gap + r * (tag + gap) - 0.5 * h);
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector2d p = tl + offsets[k];
        pts.push_back({4 * (r * s.cols + c) + k, Eigen::Vector3d(p.x(), p.y(), 0.0)});
      }
    }
  return pts;
}

std::vector<CornerObservation> detect_target(const cv::Mat& grey, const TargetSpec& spec) {
  if (grey.type() != CV_8UC1 || grey.empty()) throw std::invalid_argument("detect_target: an 8-bit grey image is needed");
  if (spec.kind == TargetKind::Checkerboard) return detect_checkerboard(grey, spec);
  if (spec.kind == TargetKind::AprilGrid) return detect_aprilgrid(grey, spec);
  throw std::invalid_argument("detect_target: checkerboard or aprilgrid only");
}

}  // namespace rsd::dsp
