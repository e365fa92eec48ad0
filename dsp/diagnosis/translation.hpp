// The translation nuisance of matches recordings: the part of each frame pair's residual that a
// camera translating past the scene explains, taken out so that effects are judged on what a
// translation cannot explain (docs/diagnosis.md, "Parallax").
//
// The translation is a smooth velocity in world axes, not a free vector per frame pair. Over a
// scene at one depth a sideways translation moves the image as a rotation does, so a free
// translation per pair would take up everything a rotation error leaves at the pair's rate: a
// clock offset (its residual follows the angular acceleration), a gyro bias, a focal length
// off under a pan. A vehicle's velocity over the scene's depth changes over about a second; in
// world axes it does not turn when the camera pans (the gyro carries that into camera axes), so
// a pan's residual, which a clock offset or a focal length leaves, stays for the effects.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "dsp/diagnosis/gyro.hpp"

namespace rsd::dsp {

class DiagnosisModel;

// The knot spacing of the velocity's cubic B-spline (s): it follows changes of velocity over
// depth slower than about 1 / (2 x spacing) Hz.
constexpr double kTranslationKnotS = 0.5;

// Removes from `r` (residuals of the observations `idx`, NaN for failed predictions) the flow of
// the camera's translation: per frame pair, the flow over one plane (translation_flow,
// parallax.hpp, times the plane's inverse depth 1 + g . (x, y) at the normalised image
// coordinates) of u(t) dt turned into camera axes, u(t) = v(t) / depth a cubic B-spline in world
// axes fitted to the inliers of every pair at once (four passes; an inlier lies within 4 robust
// scales of the current fit), the slope g (one for the recording: a ground ahead of a vehicle)
// from the second pass on. A pair needs no minimum of observations: the spline pools its
// neighbours. The camera's orientation at frame time T is
// track.camera_at(tm.motion_time(T)) mount_t, mount_t the transpose of the mount rotation
// (model.cpp, "Matches").
void remove_translation(const DiagnosisModel& m, const std::vector<int>& idx, std::vector<Eigen::Vector2d>& r,
                        const GyroTrack& track, const TimeModel& tm, const Eigen::Matrix3d& mount_t,
                        double knot_s = kTranslationKnotS);

}  // namespace rsd::dsp
