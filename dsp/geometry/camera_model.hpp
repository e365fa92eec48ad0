// The camera: pinhole intrinsics K and a lens (dsp/geometry/lens_model.hpp: pinhole-radtan or
// pinhole-equi), with their inverse. Every user of the camera (projection, rays, the rectifier's
// maps, the simulator, the diagnosis) goes through it, so each works with either lens.
//
// Pixel convention (docs/formats/recording-v1.md): u to the right, v down,
// origin at the centre of the top-left pixel. Camera axes: x right, y down, z forward.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

#include "dsp/geometry/lens_model.hpp"

namespace rsd::dsp {

struct CameraModel {
  int width = 640;
  int height = 480;
  double fx = 500, fy = 500;
  double cx = 319.5, cy = 239.5;
  Distortion dist;

  // A camera whose lens sees hfov_rad across the image's width (the focal length puts the
  // distorted radius of hfov_rad / 2 at half the width), principal point centred. Without a lens:
  // the pinhole, f = (width / 2) / tan(hfov_rad / 2); an equidistant lens without terms,
  // f = (width / 2) / (hfov_rad / 2).
  static CameraModel from_hfov(int width, int height, double hfov_rad, const Distortion& lens = {});

  // Normalised image-plane point (x/z, y/z) -> distorted normalised point (the lens).
  Eigen::Vector2d distort(const Eigen::Vector2d& xn) const { return dsp::distort(dist, xn); }
  // d(distort)/d(xn), analytic: used by the inverse and by solvers.
  Eigen::Matrix2d distort_jacobian(const Eigen::Vector2d& xn) const { return dsp::distort_jacobian(dist, xn); }
  // Inverse of distort(); nullopt where the lens has none (lens_model.hpp).
  std::optional<Eigen::Vector2d> undistort(const Eigen::Vector2d& xd) const { return dsp::undistort(dist, xd); }

  // Normalised (undistorted) point -> pixel, applying distortion.
  Eigen::Vector2d to_pixel(const Eigen::Vector2d& xn) const;
  // Pixel -> normalised undistorted point; nullopt where distortion cannot be inverted.
  std::optional<Eigen::Vector2d> from_pixel(const Eigen::Vector2d& px) const;

  // Camera-frame point -> pixel; nullopt when the point is not in front of the camera.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& Xc) const;
  // Pixel -> unit-z ray direction (x, y, 1) in camera axes.
  std::optional<Eigen::Vector3d> ray(const Eigen::Vector2d& px) const;

  bool contains(const Eigen::Vector2d& px, double margin = 0.5) const {
    return px.x() >= -margin && px.y() >= -margin && px.x() <= width - 1 + margin &&
           px.y() <= height - 1 + margin;
  }
};

// The same camera at another resolution with the same field of view: focal lengths scaled, and the
// principal point about the pixel grid's edge (pixel centres at whole numbers: c' = (c + 1/2) s - 1/2);
// the lens, on the normalised plane, unchanged.
CameraModel scaled_camera(const CameraModel& c, int width, int height);

// The largest angle off the axis (radians) that the image's corners see through the lens (0.5
// when no corner has a ray).
double widest_ray_angle(const CameraModel& cam);

// Which part of a camera lies outside rsd's input limits (dsp/core/input_limits.hpp), and how:
// what a boundary reading intrinsics reports under its own key for that part.
struct CameraOutOfRange {
  enum Part { None, Size, Focal, PrincipalPoint, Distortion } part = None;
  const char* field = "";  // width, height, fx, fy, cx, cy, k1, k2, p1, p2, k3, k4
  std::string why;         // "fx 1e+300 is outside 1..1e7 pixels"
};
CameraOutOfRange out_of_range(const CameraModel& cam);

}  // namespace rsd::dsp
