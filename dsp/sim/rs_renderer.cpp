#include "dsp/sim/rs_renderer.hpp"

#include <algorithm>
#include <cmath>

#include "dsp/geometry/rs_projection.hpp"

namespace rsd::dsp {

RsRenderer::RsRenderer(const CameraModel& cam, const RowTiming& timing, const RenderOptions& opt)
    : cam_(cam), timing_(timing), opt_(opt),
      accum_(static_cast<size_t>(cam.width) * cam.height), rng_(opt.noise_seed) {
  opt_.supersample = std::max(1, opt_.supersample);
  opt_.exposure_samples = std::max(1, opt_.exposure_samples);
}

// Colour seen along the ray through (u, v) from a camera at `centre` with world-from-camera
// rotation R_wc (the scene's colour_along_ray).
Eigen::Vector3f RsRenderer::shade(const Scene& scene, const Eigen::Vector3d& centre, const Eigen::Matrix3d& R_wc,
                                  double u, double v) const {
  const auto ray_c = cam_.ray({u, v});
  if (!ray_c) return scene.background;
  return colour_along_ray(scene, normals_, centre, R_wc, *ray_c);
}

void RsRenderer::render(const Scene& scene, const CameraMotion& motion, double t_frame, const ImageView& out) {
  const int n = opt_.supersample, ne = opt_.exposure_samples;
  const float weight = 1.0f / static_cast<float>(n * n * ne);
  normals_.clear();
  for (const Plane& p : scene.planes) normals_.push_back(p.normal());
  for (int y = 0; y < cam_.height; ++y) {
    Eigen::Vector3f* row = &accum_[static_cast<size_t>(y) * cam_.width];
    std::fill(row, row + cam_.width, Eigen::Vector3f::Zero());
    for (int e = 0; e < ne; ++e) {
      // The whole row is read at once; blur spans its exposure centred on the read time.
      const double t = t_frame + timing_.row_time(y) + timing_.exposure_s * ((e + 0.5) / ne - 0.5);
      const Eigen::Affine3d cam_from_world = motion.at(t);
      const Eigen::Matrix3d R_wc = cam_from_world.linear().transpose();
      const Eigen::Vector3d centre = -R_wc * cam_from_world.translation();
      for (int x = 0; x < cam_.width; ++x)
        for (int j = 0; j < n; ++j)
          for (int i = 0; i < n; ++i)
            row[x] += weight * shade(scene, centre, R_wc, x + (i + 0.5) / n - 0.5, y + (j + 0.5) / n - 0.5);
    }
  }
  if (!scene.points.empty()) draw_points(scene, motion, t_frame);
  for (int y = 0; y < cam_.height; ++y) write_row(out, y);
}

// Points are dots centred where the rolling-shutter constraint puts them.
void RsRenderer::draw_points(const Scene& scene, const CameraMotion& motion, double t_frame) {
  struct Shifted final : CameraMotion {
    const CameraMotion& m;
    double t0;
    Shifted(const CameraMotion& mm, double tt) : m(mm), t0(tt) {}
    Eigen::Affine3d at(double t) const override { return m.at(t0 + t); }
  } shifted(motion, t_frame);
  const double rad = scene.point_radius_px;
  for (const auto& X : scene.points) {
    const RsProjection p = project_trajectory(cam_, timing_, shifted, X);
    if (!p.ok()) continue;
    const int x0 = static_cast<int>(std::floor(p.pixel.x() - 2 * rad)), x1 = static_cast<int>(std::ceil(p.pixel.x() + 2 * rad));
    const int y0 = static_cast<int>(std::floor(p.pixel.y() - 2 * rad)), y1 = static_cast<int>(std::ceil(p.pixel.y() + 2 * rad));
    for (int y = std::max(0, y0); y <= std::min(cam_.height - 1, y1); ++y)
      for (int x = std::max(0, x0); x <= std::min(cam_.width - 1, x1); ++x) {
        const double r2 = (Eigen::Vector2d(x, y) - p.pixel).squaredNorm();
        const float a = static_cast<float>(std::exp(-0.5 * r2 / (rad * rad)));
        Eigen::Vector3f& c = accum_[static_cast<size_t>(y) * cam_.width + x];
        c = (1 - a) * c + a * Eigen::Vector3f::Ones();
      }
  }
}

void RsRenderer::write_row(const ImageView& out, int y) {
  const Eigen::Vector3f* row = &accum_[static_cast<size_t>(y) * cam_.width];
  std::uint8_t* dst = out.row(y);
  auto to8 = [&](float v) {
    float g = 255.0f * v;
    if (opt_.noise_sigma > 0) g += static_cast<float>(opt_.noise_sigma) * noise_(rng_);
    return static_cast<std::uint8_t>(std::clamp(std::lround(g), 0L, 255L));
  };
  for (int x = 0; x < cam_.width; ++x) {
    if (out.format == PixelFormat::Rgb8) {
      for (int c = 0; c < 3; ++c) dst[3 * x + c] = to8(row[x][c]);
    } else {
      dst[x] = to8((row[x][0] + row[x][1] + row[x][2]) / 3.0f);
    }
  }
}

}  // namespace rsd::dsp
