// rsd-calib import-lens: a gyroflow lens profile as an rsd-calibration/1 file for a camera of
// the given resolution (formats/gyroflow_profile.hpp).
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace rsd::tools {

struct ImportLensOptions {
  std::string profile, output;
  int width = 0, height = 0;
};

CLI::App* add_import_lens_command(CLI::App& app, ImportLensOptions& o);
int run_import_lens(const ImportLensOptions& o);

}  // namespace rsd::tools
