// A crafted LCM log through the daemon's replay path as far as it goes without threads: the
// replay source (events, frames, their timing and stamps, velocity messages), the velocity
// input's checks into a velocity buffer, and the rectifier with the log's own camera or the
// simulator's. The log parsers have their own target (fuzz_lcm_log); this one finds what a
// decodable but hostile log does to the stages after them: stamps, rates and sizes at the edges
// of rsd's input limits, time lines broken and restarted, motions beyond the model's reach.
#include <rsd/velocity_t.hpp>

#include <chrono>
#include <memory>
#include <stdexcept>

#include "daemon/frame_rectifier.hpp"
#include "daemon/velocity_buffer.hpp"
#include "drivers/replay_source.hpp"
#include "dsp/core/stamp.hpp"
#include "tests/fuzz/fuzz_input.hpp"

namespace {

using namespace rsd;

void rectify_all(drivers::ReplaySource& src) {
  daemon::VelocityBuffer velocity;
  src.set_velocity_message_sink([&](const rsd::velocity_t& m) {
    drivers::VelocitySample s;  // camera frame, as the velocity input would push it
    if (!dsp::Stamp::from_us(m.utime)) return;  // the velocity input's window
    s.t_ns = m.utime * 1000;
    for (int i = 0; i < 3; ++i) s.w[i] = m.angular_velocity[i], s.v[i] = m.linear_velocity[i];
    s.has_linear = m.has_linear;
    velocity.push(s);
  });
  src.open();
  src.start();
  const drivers::FrameFormat f = src.format();
  const dsp::CameraModel cam = src.recorded_camera().value_or(dsp::CameraModel::from_hfov(f.width, f.height, 1.0));
  daemon::RectifyConfig rc;
  rc.imu_wait_ms = 0;
  daemon::FrameRectifier rect(rc, cam, src.timing(), f);
  dsp::Image raw(f.width, f.height, f.format), out(f.width, f.height, f.format);
  drivers::FrameMeta meta;
  for (int frames = 0; frames < 16; ++frames) {
    const drivers::CaptureStatus st = src.capture(raw.view(), meta, std::chrono::milliseconds(0));
    if (st == drivers::CaptureStatus::EndOfStream) break;
    if (st == drivers::CaptureStatus::Frame) rect.process(raw.view(), out.view(), meta, velocity);
  }
  src.stop();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  drivers::ReplayConfig c;
  c.file = fuzz::write_file("replay.lcmlog", data, size);
  c.speed = 0;
  c.quiet_skips = true;
  drivers::ReplaySource src(c);
  try {
    rectify_all(src);
  } catch (const std::runtime_error&) {
    // A log without a usable frame, a camera model the rectifier refuses: documented errors.
  }
  return 0;
}
