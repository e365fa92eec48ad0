#include "tools/sim/sim_lcm_log.hpp"

#include "formats/image_t_codec.hpp"
#include "formats/lcm_log.hpp"
#include "formats/number_text.hpp"

#include <bot_core/image_t.hpp>
#include <bot_core/pose_t.hpp>
#include <rsd/velocity_t.hpp>

#include <limits>
#include <cmath>
#include <stdexcept>

namespace rsd::tools {

namespace {

int64_t to_utime(double t) { return static_cast<int64_t>(std::llround(t * 1e6)); }

void add_meta(bot_core::image_t& img, const std::string& key, const std::string& value) {
  bot_core::image_metadata_t m;
  m.key = key;
  m.value.assign(value.begin(), value.end());
  m.n = static_cast<int32_t>(m.value.size());
  img.metadata.push_back(std::move(m));
  img.nmetadata = static_cast<int32_t>(img.metadata.size());
}

template <class Msg>
void write(formats::LcmLogWriter& log, const std::string& path, const char* channel, int64_t utime, const Msg& msg) {
  std::vector<uint8_t> buf(msg.getEncodedSize());
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  if (!log.write(channel, utime, buf.data(), buf.size())) throw std::runtime_error(path + ": cannot write LCM event (disk full?)");
}

// Pose sample i as bot_core.pose_t; rates by differences over the neighbouring samples.
bot_core::pose_t pose_message(const std::vector<dsp::PoseSample>& poses, size_t i) {
  const dsp::PoseSample& s = poses[i];
  const dsp::PoseSample& lo = poses[i > 0 ? i - 1 : i];
  const dsp::PoseSample& hi = poses[i + 1 < poses.size() ? i + 1 : i];
  bot_core::pose_t m{};
  m.utime = to_utime(s.t);
  const Eigen::Quaterniond q = s.q.normalized();
  m.orientation[0] = q.w(), m.orientation[1] = q.x(), m.orientation[2] = q.y(), m.orientation[3] = q.z();
  Eigen::Vector3d w = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
  if (hi.t > lo.t) {
    const Eigen::Matrix3d R = q.toRotationMatrix();
    w = dsp::log_so3(lo.q.normalized().toRotationMatrix().transpose() * hi.q.normalized().toRotationMatrix()) / (hi.t - lo.t);
    v = R.transpose() * (hi.p - lo.p) / (hi.t - lo.t);
  }
  for (int k = 0; k < 3; ++k) m.pos[k] = s.p[k], m.vel[k] = v[k], m.rotation_rate[k] = w[k], m.accel[k] = 0;
  return m;
}

}  // namespace

void camera_velocity(const dsp::CameraMotion& motion, double t, Eigen::Vector3d& w, Eigen::Vector3d& v) {
  const double h = 1e-4;
  // Camera pose in the world: R_wc = A^T, c = -A^T b for X_c = A X_w + b.
  auto pose = [&](double tt, Eigen::Matrix3d& R, Eigen::Vector3d& c) {
    const Eigen::Affine3d g = motion.at(tt);
    R = g.linear().transpose();
    c = -R * g.translation();
  };
  Eigen::Matrix3d R0, R1, R;
  Eigen::Vector3d c0, c1, c;
  pose(t - h, R0, c0);
  pose(t + h, R1, c1);
  pose(t, R, c);
  w = dsp::log_so3(R0.transpose() * R1) / (2 * h);  // body rate: dR/dt = R [w]x
  v = R.transpose() * (c1 - c0) / (2 * h);
}

void write_sim_lcm_log(const SimLogSpec& spec, const std::vector<double>& frame_times, int width, int height,
                       dsp::PixelFormat format, const std::function<void(size_t, const dsp::ImageView&)>& render,
                       const dsp::CameraMotion& motion, const SimPoseLog& poses) {
  formats::LcmLogWriter log(spec.path);
  dsp::Image frame(width, height, format);
  const double period = 1.0 / spec.velocity_rate_hz;
  double next_velocity = frame_times.empty() ? 0 : frame_times.front() - 0.1;
  size_t next_pose = 0;
  auto write_poses_until = [&](double t_end) {
    for (; next_pose < poses.poses.size() && poses.poses[next_pose].t <= t_end; ++next_pose) {
      const bot_core::pose_t m = pose_message(poses.poses, next_pose);
      write(log, spec.path, poses.channel.c_str(), m.utime, m);
    }
  };
  for (size_t k = 0; k < frame_times.size(); ++k) {
    // Velocity messages up to this frame's end of readout, in time order with the frames.
    const double frame_end = frame_times[k] + spec.timing.frame_readout_s();
    for (; next_velocity <= frame_end; next_velocity += period) {
      rsd::velocity_t vel{};
      vel.utime = to_utime(next_velocity);
      vel.frame = rsd::velocity_t::FRAME_CAMERA;
      Eigen::Vector3d w, v;
      camera_velocity(motion, next_velocity, w, v);
      for (int i = 0; i < 3; ++i) vel.angular_velocity[i] = w[i], vel.linear_velocity[i] = v[i];
      vel.has_linear = 1;
      write(log, spec.path, kVelocityChannel, vel.utime, vel);
    }
    write_poses_until(frame_end);
    render(k, frame.view());
    bot_core::image_t img{};
    img.utime = to_utime(frame_times[k]);
    img.width = width;
    img.height = height;
    img.row_stride = static_cast<int32_t>(frame.stride());
    img.pixelformat = formats::fourcc(format);
    img.data = frame.data;
    img.size = static_cast<int32_t>(img.data.size());
    add_meta(img, "frame_utime", std::to_string(img.utime));
    add_meta(img, "line_delay_ns", formats::number_text(spec.timing.line_delay_s * 1e9));
    add_meta(img, "readout", std::string(dsp::to_string(spec.timing.readout)));
    add_meta(img, "exposure_ns", std::to_string(std::llround(spec.timing.exposure_s * 1e9)));
    add_meta(img, "sequence", std::to_string(k));
    add_meta(img, "rectified", "0");
    // The log event is stamped when the last row has been read, as a live camera would be.
    write(log, spec.path, kRawChannel, to_utime(frame_end), img);
  }
  write_poses_until(std::numeric_limits<double>::infinity());  // the trajectory's tail
}

}  // namespace rsd::tools
