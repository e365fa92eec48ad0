#include "formats/video_module_loader.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsd::formats {
namespace {

namespace fs = std::filesystem;

constexpr const char* kModuleFile = "rsd_video_opencv.so";

bool is_under(const fs::path& p, const fs::path& dir) {
  auto d = dir.begin(), q = p.begin();
  for (; d != dir.end(); ++d, ++q)
    if (q == p.end() || *d != *q) return false;
  return true;
}

// Where the module may be, most specific first (the header says why these).
std::vector<fs::path> candidates() {
  std::vector<fs::path> out;
  std::error_code ec, ec_build;
  const fs::path exe = fs::canonical("/proc/self/exe", ec);
  const fs::path build = fs::canonical(RSD_BUILD_DIR, ec_build);
  if (!ec && !ec_build && is_under(exe, build)) out.push_back(build / "formats" / kModuleFile);
  if (!ec) out.push_back((exe.parent_path() / RSD_VIDEO_MODULE_FROM_BINDIR / kModuleFile).lexically_normal());
  out.push_back(fs::path(RSD_VIDEO_MODULE_INSTALL_DIR) / kModuleFile);
  return out;
}

const video_module::Api* load() {
  std::string looked;
  for (const fs::path& p : candidates()) {
    if (!fs::exists(p)) {
      looked += (looked.empty() ? "" : ", ") + p.string();
      continue;
    }
    // Loaded for the life of the process, never closed: its objects may outlive any one caller.
    void* handle = dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) throw std::runtime_error("the video module " + p.string() + " does not load: " + dlerror());
    using Entry = const video_module::Api* (*)();
    const auto entry = reinterpret_cast<Entry>(dlsym(handle, "rsd_video_module_api"));
    const video_module::Api* api = entry ? entry() : nullptr;
    if (!api) throw std::runtime_error("the video module " + p.string() + " has no rsd_video_module_api");
    if (api->version != video_module::kVersion)
      throw std::runtime_error("the video module " + p.string() + " is version " + std::to_string(api->version) +
                               ", this program needs version " + std::to_string(video_module::kVersion) +
                               " (a module of another build of rsd: reinstall)");
    return api;
  }
  throw std::runtime_error(std::string("cannot read or write video: the video module ") + kModuleFile +
                           " is in none of " + looked + " (reinstall rsd, or build the target rsd_video_opencv)");
}

}  // namespace

const video_module::Api& video_module_api() {
  static const video_module::Api* api = load();  // a throw leaves it to the next call to try again
  return *api;
}

}  // namespace rsd::formats
