// What the daemon asks of a source that plays something recorded (an LCM log, an images
// recording) rather than a live camera: how far it is, how many frames it has delivered, and
// whether it paces itself at all (fast: no waiting, so the pipeline must drop nothing).
//
// Thread contract: progress() and frames() may be read from another thread than the one that
// captures (approximate values); the rest on the capturing thread or after it has stopped.
#pragma once

#include <cstdint>
#include <string>

namespace rsd::drivers {

class Playback {
 public:
  virtual ~Playback() = default;
  virtual double progress() const = 0;  // 0..1
  virtual uint64_t frames() const = 0;
  virtual bool fast() const = 0;
  // One line for the closing summary: what was played, from where, what was skipped.
  virtual std::string summary(double seconds) const = 0;
};

}  // namespace rsd::drivers
