#include "formats/motion_log.hpp"

#include <bot_core/image_t.hpp>
#include <bot_core/pose_t.hpp>
#include <rsd/velocity_t.hpp>

#include <algorithm>
#include <stdexcept>

#include "formats/image_t_codec.hpp"
#include "formats/lcm_log.hpp"

namespace rsd::formats {

namespace {

// A raw frame as every rsd reader takes it (formats/image_t_codec.hpp: fingerprint, sizes,
// the one timestamp rule); a frame that does not decode is an error naming the event.
LogFrame frame_meta(const LogEvent& ev, bot_core::image_t& img, const std::string& where) {
  RecordedFrame f;
  std::string why;
  if (decode_frame(ev.data.data(), ev.data.size(), img, f, why) != DecodeStatus::Ok)
    throw std::runtime_error(where + ": " + why);
  if (f.line_delay_s && *f.line_delay_s < 0) throw std::runtime_error(where + ": negative line delay in the metadata");
  return {f.meta.first_row_ns * 1e-9, f.line_delay_s, f.readout, f.format.width, f.format.height};
}

void add_velocity(const LogEvent& ev, MotionLog& s, std::vector<double>& speeds, const std::string& where) {
  rsd::velocity_t m{};
  std::string why;
  if (decode_checked(ev.data.data(), ev.data.size(), m, why) != DecodeStatus::Ok ||
      (m.frame != rsd::velocity_t::FRAME_CAMERA && m.frame != rsd::velocity_t::FRAME_IMU)) {
    ++s.malformed;  // not an rsd.velocity_t, or a frame this version does not know
    return;
  }
  if (s.gyro_frame && *s.gyro_frame != m.frame)
    throw std::runtime_error(where + ": velocity frame changes between camera and IMU axes within the log");
  s.gyro_frame = m.frame;
  const Eigen::Vector3d w(m.angular_velocity[0], m.angular_velocity[1], m.angular_velocity[2]);
  if (!w.allFinite()) return void(++s.malformed);
  s.gyro.push_back({m.utime * 1e-6, w});
  const Eigen::Vector3d v(m.linear_velocity[0], m.linear_velocity[1], m.linear_velocity[2]);
  if (m.has_linear && v.allFinite()) speeds.push_back(v.norm());
}

void add_pose(const LogEvent& ev, MotionLog& s) {
  bot_core::pose_t m{};
  std::string why;
  if (decode_checked(ev.data.data(), ev.data.size(), m, why) != DecodeStatus::Ok) return void(++s.malformed);
  const Eigen::Quaterniond q(m.orientation[0], m.orientation[1], m.orientation[2], m.orientation[3]);
  const Eigen::Vector3d p(m.pos[0], m.pos[1], m.pos[2]);
  if (!p.allFinite() || !q.coeffs().allFinite() || q.norm() < 0.5) return void(++s.malformed);
  s.poses.push_back({m.utime * 1e-6, p, q.normalized()});
}

}  // namespace

MotionLog read_motion_log(const std::string& path, const MotionLogChannels& ch,
                          const std::function<void(uint64_t, uint64_t)>& progress) {
  LcmLogReader log(path);
  LogEvent ev;
  bot_core::image_t img;
  MotionLog s;
  std::vector<double> speeds;
  while (log.next(ev)) {
    const int event = ++s.events;
    ++s.channels[ev.channel];
    const std::string where = path + ": event " + std::to_string(event) + " on " + ev.channel;
    if (ev.channel == ch.image) {
      s.frames.push_back(frame_meta(ev, img, where));
      const LogFrame& f = s.frames.back();
      if (f.width != s.frames.front().width || f.height != s.frames.front().height)
        throw std::runtime_error(where + ": frame is " + std::to_string(f.width) + "x" + std::to_string(f.height) + ", the first was " +
                                 std::to_string(s.frames.front().width) + "x" + std::to_string(s.frames.front().height));
      if (progress) progress(log.position(), log.size());
    } else if (ev.channel == ch.velocity) {
      add_velocity(ev, s, speeds, where);
    } else if (ev.channel == ch.pose) {
      add_pose(ev, s);
    }
  }
  if (progress) progress(log.size(), log.size());
  s.with_translation = static_cast<int>(speeds.size());
  if (!speeds.empty()) {
    std::nth_element(speeds.begin(), speeds.begin() + speeds.size() / 2, speeds.end());
    s.median_speed_m_s = speeds[speeds.size() / 2];
    s.max_speed_m_s = *std::max_element(speeds.begin(), speeds.end());
  }
  // Motion may be logged out of order (several publishers): recording-v1 wants it ordered.
  std::stable_sort(s.gyro.begin(), s.gyro.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  std::stable_sort(s.poses.begin(), s.poses.end(), [](const auto& a, const auto& b) { return a.t < b.t; });
  return s;
}

std::string channel_list(const MotionLog& s) {
  std::string list;
  for (const auto& [name, n] : s.channels) list += (list.empty() ? "" : ", ") + name + " (" + std::to_string(n) + ")";
  return list;
}

}  // namespace rsd::formats
