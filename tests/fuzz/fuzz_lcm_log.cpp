// LCM log files (formats/lcm_log.hpp) and what rsd decodes from their events: raw frames
// (bot_core.image_t with row timing), velocity, poses, frame info and health.
#include <bot_core/pose_t.hpp>
#include <rsd/frame_info_t.hpp>
#include <rsd/health_t.hpp>
#include <rsd/velocity_t.hpp>

#include "formats/image_t_codec.hpp"
#include "formats/lcm_log.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  rsd::formats::LcmLogReader reader(rsd::fuzz::write_file("run.lcmlog", data, size));
  reader.set_message_handler({});
  rsd::formats::LogEvent ev;
  std::string why;
  bot_core::image_t img;
  rsd::formats::RecordedFrame frame;
  while (reader.next(ev)) {
    const uint8_t* p = ev.data.data();
    const size_t n = ev.data.size();
    rsd::formats::decode_frame(p, n, img, frame, why);
    rsd::velocity_t v;
    rsd::formats::decode_checked(p, n, v, why);
    bot_core::pose_t pose;
    rsd::formats::decode_checked(p, n, pose, why);
    rsd::frame_info_t info;
    rsd::formats::decode_checked(p, n, info, why);
    rsd::health_t health;
    rsd::formats::decode_checked(p, n, health, why);
  }
  return 0;
}
