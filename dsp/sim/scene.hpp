// What the simulated camera looks at: textured planes and point sets, in world coordinates.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <vector>

#include "dsp/core/image.hpp"

namespace rsd::dsp {

// Intensity (0..1, per channel) of a plane's surface at plane coordinates (s, t) in metres.
class Texture {
 public:
  virtual ~Texture() = default;
  virtual Eigen::Vector3f colour(double s, double t) const = 0;
};

// Black and white squares; (0, 0) is the outer corner of a black square. Outside the
// board's squares a white margin of one square.
class CheckerboardTexture final : public Texture {
 public:
  CheckerboardTexture(int cols, int rows, double square_m) : cols_(cols), rows_(rows), sq_(square_m) {}
  Eigen::Vector3f colour(double s, double t) const override;
  // Inner corners (where four squares meet), in plane coordinates, row-major.
  std::vector<Eigen::Vector2d> inner_corners() const;

 private:
  int cols_, rows_;
  double sq_;
};

// Smooth random texture (value noise over several octaves, in colour): rich in
// features for tracking, with no periodicity.
class NoiseTexture final : public Texture {
 public:
  NoiseTexture(unsigned seed, double cell_m);
  Eigen::Vector3f colour(double s, double t) const override;

 private:
  std::uint64_t lattice_key(long i, long j) const;
  static float lattice(std::uint64_t key, int channel);
  static constexpr int kOctaves = 4;
  struct LatticeCell;
  void octave(double s, double t, LatticeCell& cell, float v[3]) const;
  unsigned seed_;
  double cell_;
};

// A printed picture: plane coordinates (s, t) in metres map to bitmap pixels with
// `pixels_per_m`, (0, 0) at the bitmap's top-left corner; bilinear, white outside.
class BitmapTexture final : public Texture {
 public:
  BitmapTexture(Image bitmap, double pixels_per_m) : img_(std::move(bitmap)), ppm_(pixels_per_m) {}
  Eigen::Vector3f colour(double s, double t) const override;
  double width_m() const { return img_.width / ppm_; }
  double height_m() const { return img_.height / ppm_; }

 private:
  Eigen::Vector3f texel(int x, int y) const;
  Image img_;
  double ppm_;
};

struct Plane {
  Eigen::Vector3d origin;  // world position of plane coordinate (0, 0)
  Eigen::Vector3d axis_s;  // unit vectors of the plane coordinates, world frame
  Eigen::Vector3d axis_t;
  // The plane exists for plane coordinates s in [s_min, s_max], t in [t_min, t_max].
  double s_min = -1e9, s_max = 1e9, t_min = -1e9, t_max = 1e9;
  std::shared_ptr<const Texture> texture;
  Eigen::Vector3d normal() const { return axis_s.cross(axis_t).normalized(); }
};

struct Scene {
  std::vector<Plane> planes;
  std::vector<Eigen::Vector3d> points;  // rendered as bright dots of radius point_radius_px
  double point_radius_px = 1.5;
  Eigen::Vector3f background{0.2f, 0.2f, 0.2f};
};

// The colour a ray sees: from `centre` along the camera-axes direction `ray_c` turned into the
// world by R_wc, the nearest plane it meets inside the plane's extent, else the background.
// `normals` holds each plane's normal (a renderer computes them once a frame, not once a ray).
Eigen::Vector3f colour_along_ray(const Scene& scene, const std::vector<Eigen::Vector3d>& normals,
                                 const Eigen::Vector3d& centre, const Eigen::Matrix3d& R_wc, const Eigen::Vector3d& ray_c);

// A plane facing the camera (s along x, t along y, the camera looking down +z), unbounded,
// with plane coordinate (0, 0) at `origin`.
Plane fronto_parallel(const Eigen::Vector3d& origin, std::shared_ptr<const Texture> texture);

// A plane facing the camera at distance z (camera looking down +z from the world origin),
// holding a checkerboard centred on the optical axis.
Plane fronto_parallel_checkerboard(double z, int cols, int rows, double square_m);

}  // namespace rsd::dsp
