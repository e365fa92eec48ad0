// Finds and loads the video module (formats/video_module.hpp) the first time a process asks for it.
//
// Where: beside the build tree's formats/ when the running program lives in the build tree that
// made it (tests, a developer's run), else in the installation's library folder relative to the
// program's (bin/../lib/<arch>/rsd), else in the configured prefix's. Never from a path the
// environment names: the daemon runs as a service.
//
// Thread contract: any thread; the first call loads (once), the others wait for it.
#pragma once

#include "formats/video_module.hpp"

namespace rsd::formats {

// The module's entry points; throws std::runtime_error naming the places looked in, or the
// module and what dlopen said, when there is no usable module.
const video_module::Api& video_module_api();

}  // namespace rsd::formats
