// Domain of applicability of the pinhole model (the paper's Sec. "Domain of applicability"):
// when does the rolling-shutter correction term of eq. (4) stay below a
// pixel, so that a perspective (global-shutter) model is good enough?
//
// Units: depths in metres, v in m/s, w in rad/s, corrections in pixels. The row rate r
// is RowTiming::r() (rows/s); on the unit-focal image plane it is r_n = r / fy, and a
// pixel there is s_alpha = 1 / fy long. See docs/applicability.md.
#pragma once

#include <Eigen/Core>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/geometry/camera_motion.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

// The paper's limit line, v_y / (s_alpha r) < z, read in normalised units
// (s_alpha = 1/fy, r_n = r/fy) and generalised to a threshold of max_px pixels:
//     z_min = |v_y| / (max_px s_alpha |r_n|) = |v_y| fy^2 / (max_px |r|)   [m].
// Beyond z_min the paper deems the pinhole model sufficient. v_y in m/s. Returns NaN
// when max_px is not positive or the row rate is not finite and non-zero.
double paper_min_depth(const CameraModel& cam, const RowTiming& timing, double v_y,
                       double max_px = 1.0);

// Which perspective projection the rolling-shutter image is compared with.
enum class CorrectionReference {
  FrameStart,  // perspective projection at t = 0 (the paper's q(0); the default)
  MiddleRow,   // perspective projection at the time the readout passes the middle row
};
const char* to_string(CorrectionReference r);
// Parses "frame_start" / "middle_row"; false on anything else.
bool parse_correction_reference(const char* s, CorrectionReference& out);

struct ApplicabilityOptions {
  double threshold_px = 1.0;  // verdict threshold on the largest correction (pixels)
  int grid_cols = 33;         // grid over the image, borders and corners included
  int grid_rows = 25;
  CorrectionReference reference = CorrectionReference::FrameStart;
};

// Grid size for a requested number of columns: rows in proportion to the image's aspect
// (33 columns on 640 x 480 give 33 x 25). Both at least 2.
ApplicabilityOptions grid_for(const CameraModel& cam, int cols, ApplicabilityOptions base = {});

struct ApplicabilityResult {
  double max_correction_px = 0;   // largest |q_rs - q_ref| over the grid (+inf if none solved)
  double mean_correction_px = 0;  // mean over the grid points that have a solution
  Eigen::Vector2d worst_pixel = Eigen::Vector2d::Zero();       // grid pixel p of the maximum
  Eigen::Vector2d worst_correction = Eigen::Vector2d::Zero();  // q_rs - q_ref there (px)
  int grid_points = 0;
  int no_solution = 0;  // grid points the rolling-shutter constraint has no root for
  double threshold_px = 1.0;
  // max_correction_px < threshold_px and every grid point had a solution (a point the
  // readout never catches within half a frame of the image is no sub-pixel effect).
  bool pinhole_sufficient = true;
};

// The general bound: for a fronto-parallel scene at depth depth_z (metres, in the camera
// frame at frame start), each grid pixel p gives X = depth_z K^-1 p; X's rolling-shutter
// image q_rs under constant (v, w) without linearisation (project_screw) is compared with
// its perspective image (q_ref = p at frame start, or the projection at the middle row's
// time). Any v, w. Lens distortion is honoured through K^-1 and project_screw.
ApplicabilityResult correction_bound(const CameraModel& cam, const RowTiming& timing,
                                     const Twist& tw, double depth_z,
                                     const ApplicabilityOptions& opt = {});

// The smallest depth (metres) beyond which correction_bound says "pinhole sufficient"
// at every larger depth, found by bracketing then bisection on log(depth) (relative
// accuracy ~1e-9). Returns +inf when no depth suffices (the depth-independent floor of
// a rotation w != 0 reaches the threshold), 0 when every depth down to 1e-6 m suffices
// (e.g. no motion).
double min_depth_for(const CameraModel& cam, const RowTiming& timing, const Twist& tw,
                     const ApplicabilityOptions& opt = {});

}  // namespace rsd::dsp
