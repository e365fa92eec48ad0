#include "dsp/sim/aprilgrid.hpp"

#include <opencv2/aruco.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <stdexcept>

namespace rsd::dsp {

AprilGridTarget make_aprilgrid(const AprilGridSpec& spec, int pixels_per_bit) {
  if (spec.rows < 1 || spec.cols < 1 || spec.rows * spec.cols > 587)
    throw std::invalid_argument("aprilgrid: rows x cols must be 1..587 (tag36h11 has 587 codes)");
  if (!(spec.tag_size_m > 0) || !(spec.spacing > 0)) throw std::invalid_argument("aprilgrid: tag size and spacing must be positive");
  const auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_APRILTAG_36h11);
  const int tag_px = 8 * pixels_per_bit;  // 6 x 6 data bits plus a one-bit black border
  const int gap_px = static_cast<int>(std::lround(spec.spacing * tag_px));
  AprilGridTarget t;
  t.pixels_per_m = tag_px / spec.tag_size_m;
  const double gap_m = gap_px / t.pixels_per_m;  // the gap as drawn
  const int grid_w = spec.cols * tag_px + (spec.cols + 1) * gap_px, grid_h = spec.rows * tag_px + (spec.rows + 1) * gap_px;
  cv::Mat img(grid_h + 2 * gap_px, grid_w + 2 * gap_px, CV_8UC1, cv::Scalar(255));
  const cv::Rect grid(gap_px, gap_px, grid_w, grid_h);
  // Black squares at every crossing of the gaps (what Kalibr's detector uses to refine).
  for (int r = 0; r <= spec.rows; ++r)
    for (int c = 0; c <= spec.cols; ++c)
      img(cv::Rect(grid.x + c * (tag_px + gap_px), grid.y + r * (tag_px + gap_px), gap_px, gap_px)).setTo(0);
  for (int r = 0; r < spec.rows; ++r)
    for (int c = 0; c < spec.cols; ++c) {
      const int id = r * spec.cols + c;
      cv::Mat tag;
      dict->drawMarker(id, tag_px, tag, 1);
      const int x = grid.x + gap_px + c * (tag_px + gap_px), y = grid.y + gap_px + r * (tag_px + gap_px);
      tag.copyTo(img(cv::Rect(x, y, tag_px, tag_px)));
      const double s0 = (gap_px + c * (tag_px + gap_px)) / t.pixels_per_m, t0 = (gap_px + r * (tag_px + gap_px)) / t.pixels_per_m;
      const Eigen::Vector2d tl(s0, t0);
      const Eigen::Vector2d offsets[4] = {{0, 0}, {spec.tag_size_m, 0}, {spec.tag_size_m, spec.tag_size_m}, {0, spec.tag_size_m}};
      for (int k = 0; k < 4; ++k) {
        t.corner_ids.push_back(4 * id + k);
        t.corners.push_back(tl + offsets[k]);
      }
    }
  t.width_m = grid_w / t.pixels_per_m;
  t.height_m = grid_h / t.pixels_per_m;
  t.grid_origin_in_bitmap_m = Eigen::Vector2d(gap_m, gap_m);
  t.bitmap = dsp::Image(img.cols, img.rows, dsp::PixelFormat::Mono8);
  for (int y = 0; y < img.rows; ++y) std::copy(img.ptr<uint8_t>(y), img.ptr<uint8_t>(y) + img.cols, t.bitmap.data.data() + y * t.bitmap.stride());
  return t;
}

}  // namespace rsd::dsp
