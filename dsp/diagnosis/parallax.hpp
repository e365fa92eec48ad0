// Parallax in matches recordings. The model of matches is rotation-only (the scene at
// infinity); a camera that also translates past a near scene displaces each frame pair's
// matches by the flow of that translation, which no effect of the table describes. Here: the
// flow fields of a small rotation and of a translation over a fronto-parallel scene between
// two frames (the instantaneous motion field, per unit of rotation and of translation over
// depth), and the parallax signal: whether a translation explains a pair's residual beyond a
// rotation. The translation nuisance that takes it out is translation.hpp's.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "dsp/diagnosis/instrument.hpp"
#include "dsp/geometry/camera_model.hpp"

namespace rsd::dsp {

class DiagnosisModel;

// d(pixel) per unit rotation (columns: about x, y, z) and per unit translation over depth
// (columns: along x, y, z), at `pixel`, in pixels.
Eigen::Matrix<double, 2, 3> rotation_flow(const CameraModel& cam, const Eigen::Vector2d& pixel);
// The same at normalised image coordinates xn = ((u - cx) / fx, (v - cy) / fy).
Eigen::Matrix<double, 2, 3> rotation_flow_at(const CameraModel& cam, const Eigen::Vector2d& xn);
Eigen::Matrix<double, 2, 3> translation_flow(const CameraModel& cam, const Eigen::Vector2d& pixel);

// Matches: whether a translation of the camera between the two frames of each pair explains
// the inlier residuals of `p` beyond a small rotation of it (z-score of the extra chi-square
// over its 3 degrees of freedom per pair), and the share of the residual energy the
// translation explains, net of what noise explains by chance, and what it explains beyond the
// rotation as an RMS per coordinate (net of noise too). Zero for landmarks. Uses at most 20000
// of idx. Clear at 4 sigma, 5% of the energy and the instrument's own bias (instrument.hpp): an
// independent renderer's pictures of a scene at infinity, tracked to 0.042 px, left 0.0075 px
// that a translation's flow took beyond a rotation's, 106 sigma and 63% of the residual's
// energy; the scene was taken for a near one and the selection ran under the translation
// nuisance (the gyro bias went unnamed at 640 x 360, too small beside it).
struct Parallax {
  double share = 0, z = 0, rms_px = 0;
  int pairs = 0;
  bool clear() const { return z > 4 && share >= 0.05 && rms_px >= kInstrumentBiasPx; }
};
struct ModelParams;
Parallax parallax_signal(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx);

}  // namespace rsd::dsp
