#include "drivers/sim_source.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <ctime>
#include <thread>

#include "dsp/core/pixel_conversion.hpp"

namespace rsd::drivers {

// The camera's pose: its own rate w(t) = w0 + wobble sin(2 pi f t) about each axis and a
// constant velocity, integrated in closed form per axis-independent small steps is not
// needed: we integrate the rate analytically as a rotation vector (w0 t + wobble term),
// which is exact for the rotation about a fixed axis pattern we use and smooth otherwise.
class SimSource::Motion final : public dsp::CameraMotion {
 public:
  explicit Motion(const SimSourceConfig& c) : c_(c) {}
  // Rotation vector of the camera in the world: integral of the rate.
  Eigen::Vector3d phi(double t) const {
    Eigen::Vector3d phi = c_.angular_rate * t;
    for (int i = 0; i < 3; ++i) {
      const double w = 2 * M_PI * c_.wobble_hz * c_.wobble_axes_hz[i];
      phi[i] += c_.wobble_rad_s * c_.wobble_axes[i] * (1 - std::cos(w * t)) / w;
    }
    return phi;
  }
  Eigen::Affine3d at(double t) const override {
    const Eigen::Matrix3d R_wc = dsp::exp_so3(phi(t));
    const Eigen::Vector3d c = c_.velocity * t;  // along the world axes the camera started with
    Eigen::Affine3d g = Eigen::Affine3d::Identity();
    g.linear() = R_wc.transpose();
    g.translation() = -R_wc.transpose() * c;
    return g;
  }

 private:
  SimSourceConfig c_;
};

namespace {

// The wall's texture, evaluated once into a bitmap: procedural noise costs far too much per
// pixel for a live camera, a bilinear lookup does not. It covers what the camera sees at
// that depth while it moves for a minute or so; beyond it the wall is white.
std::shared_ptr<dsp::Texture> baked_noise(unsigned seed, double depth_m) {
  const dsp::NoiseTexture noise(seed, 0.08);
  const int n = 2048;
  const double size_m = 6.0 * depth_m, ppm = n / size_m;
  dsp::Image img(n, n, dsp::PixelFormat::Rgb8);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Eigen::Vector3f c = noise.colour((x + 0.5) / ppm - 0.5 * size_m, (y + 0.5) / ppm - 0.5 * size_m);
      for (int k = 0; k < 3; ++k) img.data[(static_cast<size_t>(y) * n + x) * 3 + k] = static_cast<uint8_t>(255.0f * c[k] + 0.5f);
    }
  return std::make_shared<dsp::BitmapTexture>(std::move(img), ppm);
}

}  // namespace

SimSource::SimSource(SimSourceConfig cfg) : cfg_(std::move(cfg)), rng_(cfg_.seed) {}
SimSource::~SimSource() = default;

void SimSource::open() {
  timing_ = dsp::RowTiming::full_frame(cfg_.camera.height, cfg_.fps, cfg_.readout);
  if (cfg_.line_delay_s > 0) timing_.line_delay_s = cfg_.line_delay_s;
  if (cfg_.global_shutter) timing_.line_delay_s = 0;
  timing_.exposure_s = cfg_.exposure_s;
  if (timing_.frame_readout_s() > timing_.frame_period_s() * (1 + 1e-9))
    throw CameraError("sim: line delay x height exceeds the frame period");
  motion_ = std::make_unique<Motion>(cfg_);
  dsp::RenderOptions ro;
  ro.supersample = cfg_.supersample;
  ro.noise_sigma = cfg_.noise_grey;
  ro.noise_seed = cfg_.seed;
  renderer_ = std::make_unique<dsp::RsRenderer>(cfg_.camera, timing_, ro);
  if (cfg_.format != dsp::PixelFormat::Mono8 && cfg_.format != dsp::PixelFormat::Rgb8)
    rgb_ = dsp::Image(cfg_.camera.width, cfg_.camera.height, dsp::PixelFormat::Rgb8);
  const double z = cfg_.scene_depth_m;
  scene_.planes = {dsp::fronto_parallel(Eigen::Vector3d(-3.0 * z, -3.0 * z, z), baked_noise(cfg_.seed, z))};
}

FrameFormat SimSource::format() const { return {cfg_.camera.width, cfg_.camera.height, cfg_.format}; }

const dsp::CameraMotion& SimSource::truth() const { return *motion_; }

void SimSource::start() {
  t0_ns_ = monotonic_ns();
  frame_ = 0;
  next_velocity_s_ = 0;
}

void SimSource::emit_velocity_until(double t_s) {
  if (!sink_ || !cfg_.publish_velocity) return;
  std::normal_distribution<double> n(0, 1);
  const Eigen::Vector3d r = cfg_.imu_mount_rotation_rad;
  const Eigen::Matrix3d R_imu_to_cam =
      r.norm() > 0 ? Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix() : Eigen::Matrix3d::Identity();
  const bool imu_frame = r.norm() > 0 || cfg_.gyro_scale != Eigen::Vector3d::Ones() || cfg_.imu_time_offset_s != 0 ||
                         cfg_.gyro_bias != Eigen::Vector3d::Zero();
  for (; next_velocity_s_ <= t_s - cfg_.velocity_latency_s; next_velocity_s_ += 1.0 / cfg_.velocity_rate_hz) {
    const double t = next_velocity_s_, h = 1e-5;
    const Eigen::Matrix3d Ra = motion_->at(t - h).linear().transpose(), Rb = motion_->at(t + h).linear().transpose();
    const Eigen::Vector3d w = dsp::log_so3(Ra.transpose() * Rb) / (2 * h);  // body rate, camera axes
    const Eigen::Vector3d v = motion_->at(t).linear() * cfg_.velocity;      // velocity in camera axes
    VelocitySample s;
    s.imu_frame = imu_frame;
    s.t_ns = t0_ns_ + static_cast<int64_t>(std::llround((t + cfg_.imu_time_offset_s) * 1e9));
    const Eigen::Vector3d w_imu = R_imu_to_cam.transpose() * w, v_imu = R_imu_to_cam.transpose() * v;
    for (int i = 0; i < 3; ++i) {
      s.w[i] = w_imu[i] / cfg_.gyro_scale[i] + cfg_.gyro_bias[i] + cfg_.velocity_noise * n(rng_);
      s.v[i] = v_imu[i];
    }
    s.has_linear = true;
    sink_(s);
  }
}

CaptureStatus SimSource::capture(const dsp::ImageView& dst, FrameMeta& meta, std::chrono::milliseconds timeout) {
  const double t_frame = static_cast<double>(frame_) / cfg_.fps;
  // A frame is complete once its last row has been read (plus the exposure).
  const int64_t ready_ns = t0_ns_ + static_cast<int64_t>((t_frame + timing_.frame_readout_s() + timing_.exposure_s) * 1e9);
  if (cfg_.realtime) {
    const int64_t now = monotonic_ns();
    if (ready_ns - now > std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count()) {
      std::this_thread::sleep_for(timeout);
      return CaptureStatus::Timeout;
    }
    if (ready_ns > now) std::this_thread::sleep_for(std::chrono::nanoseconds(ready_ns - now));
  }
  if (rgb_.data.empty()) {
    renderer_->render(scene_, *motion_, t_frame, dst);
  } else {
    renderer_->render(scene_, *motion_, t_frame, rgb_.view());
    dsp::convert_from_rgb(rgb_.view(), dst);
  }
  meta.first_row_ns = t0_ns_ + static_cast<int64_t>(std::llround(t_frame * 1e9));
  meta.sequence = frame_++;
  meta.exposure_s = timing_.exposure_s;
  // Through the frame's last row and one sample beyond: every row's rate is then bracketed
  // by samples the frame's consumers already have.
  emit_velocity_until(t_frame + timing_.frame_readout_s() + timing_.exposure_s + 1.0 / cfg_.velocity_rate_hz);
  return CaptureStatus::Frame;
}

}  // namespace rsd::drivers
