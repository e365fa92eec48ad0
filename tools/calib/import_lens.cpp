#include "tools/calib/import_lens.hpp"

#include <iostream>

#include "dsp/core/input_limits.hpp"
#include "formats/calibration_v1.hpp"
#include "formats/gyroflow_profile.hpp"
#include "tools/common/cli_util.hpp"

namespace rsd::tools {

CLI::App* add_import_lens_command(CLI::App& app, ImportLensOptions& o) {
  CLI::App* c = app.add_subcommand(
      "import-lens",
      "Write a calibration file from a gyroflow lens profile (JSON): its fisheye lens (OpenCV's fisheye\n"
      "model, rsd's pinhole-equi) scaled from the profile's calib_dimension to WIDTH x HEIGHT, and the\n"
      "nominal line delay from its frame_readout_time (0, a global shutter, when the profile has none:\n"
      "rsd-diagnose or the daemon's online calibration can find it)");
  c->add_option("PROFILE", o.profile, "The gyroflow lens profile (.json)")->required()->check(CLI::ExistingFile);
  const auto side = int_range(dsp::limits::kMinSide, dsp::limits::kMaxSide);
  c->add_option("--width", o.width, "The camera's frame width (pixels)")->required()->check(side);
  c->add_option("--height", o.height, "The camera's frame height (pixels)")->required()->check(side);
  c->add_option("-o,--output", o.output, "The calibration file to write (rsd-calibration/1)")->required();
  return c;
}

int run_import_lens(const ImportLensOptions& o) {
  require_writable(o.output, "--output");
  const formats::GyroflowProfile p = formats::read_gyroflow_profile(o.profile);
  formats::Calibration c;
  c.cam = formats::profile_camera_at(p, o.profile, o.width, o.height);
  c.line_delay_s = p.frame_readout_s ? *p.frame_readout_s / o.height : 0.0;
  c.readout = p.readout;
  c.source = "gyroflow lens profile " + p.name;
  formats::write_calibration(o.output, c);
  std::cout << "Wrote " << o.output << ": " << p.name << " at " << o.width << "x" << o.height << " (calibrated at "
            << p.cam.width << "x" << p.cam.height << "): fx " << format_fixed(c.cam.fx, 2) << ", fy "
            << format_fixed(c.cam.fy, 2) << ", cx " << format_fixed(c.cam.cx, 2) << ", cy " << format_fixed(c.cam.cy, 2)
            << ", pinhole-equi k1..k4 " << format_number(c.cam.dist.k1, 6) << ", " << format_number(c.cam.dist.k2, 6)
            << ", " << format_number(c.cam.dist.k3, 6) << ", " << format_number(c.cam.dist.k4, 6) << "\n";
  if (p.frame_readout_s)
    std::cout << "Line delay " << format_number(c.line_delay_s, 6) << " s (frame readout "
              << format_number(*p.frame_readout_s * 1e3, 6) << " ms over " << o.height << " rows)\n";
  else
    std::cout << "The profile has no frame readout time: line delay 0 (a global shutter) until one is measured\n";
  return 0;
}

}  // namespace rsd::tools
