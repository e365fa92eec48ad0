// Finding and opening an Aravis device, and the small GLib ownership helpers the Aravis
// source uses. Cameras are opened by address only: asking for one by name would broadcast a
// discovery on the network.
#pragma once

#include <arv.h>

#include <memory>
#include <string>

#include "drivers/camera_source.hpp"
#include "dsp/core/image.hpp"

namespace rsd::drivers::aravis {

struct GObjectUnref {
  void operator()(gpointer p) const { g_object_unref(p); }
};
template <class T>
using GPtr = std::unique_ptr<T, GObjectUnref>;

// A GError filled by an Aravis call, freed on scope exit.
class GErr {
 public:
  GErr() = default;
  GErr(const GErr&) = delete;
  GErr& operator=(const GErr&) = delete;
  ~GErr() {
    if (e_) g_error_free(e_);
  }
  GError** out() { return &e_; }
  explicit operator bool() const { return e_ != nullptr; }
  std::string message() const { return e_ ? e_->message : "unknown error"; }
  // A transport failure means the camera went away; anything else is the camera refusing.
  bool transport() const {
    if (!e_ || e_->domain != ARV_DEVICE_ERROR) return false;
    return e_->code == ARV_DEVICE_ERROR_TIMEOUT || e_->code == ARV_DEVICE_ERROR_NOT_CONNECTED ||
           e_->code == ARV_DEVICE_ERROR_TRANSFER_ERROR;
  }

 private:
  GError* e_ = nullptr;
};

struct FormatName {
  const char* config;  // as rsd's configuration spells it
  const char* sfnc[2];  // the camera's PixelFormat entries that mean it, preferred first
  ArvPixelFormat arv;
  dsp::PixelFormat dsp;
};
constexpr FormatName kFormats[] = {
    {"Mono8", {"Mono8", nullptr}, ARV_PIXEL_FORMAT_MONO_8, dsp::PixelFormat::Mono8},
    {"Mono16", {"Mono16", nullptr}, ARV_PIXEL_FORMAT_MONO_16, dsp::PixelFormat::Mono16},
    {"RGB8", {"RGB8", "RGB8Packed"}, ARV_PIXEL_FORMAT_RGB_8_PACKED, dsp::PixelFormat::Rgb8},
    {"RGB8Packed", {"RGB8", "RGB8Packed"}, ARV_PIXEL_FORMAT_RGB_8_PACKED, dsp::PixelFormat::Rgb8},
};

const FormatName* find_format(const std::string& name);
bool is_fake(const std::string& id);
// Throws std::invalid_argument unless `id` is one camera's IPv4 address or Fake_<serial>.
void check_camera_id(const std::string& id);
// The camera at an IPv4 address, or Aravis' in-process fake; throws CameraError saying why not.
GPtr<ArvDevice> open_device(const std::string& id);

// GCallback is void (*)(void); going through it keeps -Wcast-function-type quiet.
template <class F>
GCallback as_gcallback(F* f) {
  return reinterpret_cast<GCallback>(reinterpret_cast<void (*)()>(f));
}


}  // namespace rsd::drivers::aravis
