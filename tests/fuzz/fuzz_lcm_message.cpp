// One LCM message as the network brings it (the lcm source, the velocity input): the first
// byte picks the type, the rest is the payload.
#include <bot_core/pose_t.hpp>
#include <rsd/calibration_t.hpp>
#include <rsd/frame_info_t.hpp>
#include <rsd/health_t.hpp>
#include <rsd/velocity_t.hpp>

#include "formats/image_t_codec.hpp"
#include "tests/fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const uint8_t* p = data + 1;
  const size_t n = size - 1;
  std::string why;
  switch (data[0] % 6) {
    case 0: {
      bot_core::image_t img;
      rsd::formats::RecordedFrame frame;
      if (rsd::formats::decode_frame(p, n, img, frame, why) == rsd::formats::DecodeStatus::Ok) {
        // What the sources do next with a good frame: its pixels and its row timing.
        rsd::dsp::Image out(frame.format.width, frame.format.height, frame.format.format);
        rsd::formats::copy_pixels(img, out.view());
        rsd::formats::row_timing(frame, 30);
      }
      break;
    }
    case 1: {
      rsd::velocity_t m;
      rsd::formats::decode_checked(p, n, m, why);
      break;
    }
    case 2: {
      bot_core::pose_t m;
      rsd::formats::decode_checked(p, n, m, why);
      break;
    }
    case 3: {
      rsd::frame_info_t m;
      rsd::formats::decode_checked(p, n, m, why);
      break;
    }
    case 4: {
      rsd::calibration_t m;
      rsd::formats::decode_checked(p, n, m, why);
      break;
    }
    default: {
      rsd::health_t m;
      rsd::formats::decode_checked(p, n, m, why);
    }
  }
  return 0;
}
