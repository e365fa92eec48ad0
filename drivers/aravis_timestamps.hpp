// What an Aravis buffer says about when and which frame it is, turned into FrameMeta terms:
// CLOCK_MONOTONIC start of exposure of the first row, and a counter whose gaps are drops.
// Nothing here touches Aravis, so every rule is unit-tested on synthetic stamp sequences.
//
// An Aravis 0.8 buffer carries two stamps:
//  - arv_buffer_get_timestamp: the camera's own clock in ns (GigE Vision: the GVSP leader's
//    timestamp scaled by the device's tick frequency). Precise frame to frame, but on a clock
//    of its own, with an unknown offset and a rate error of up to ~100 ppm (its crystal).
//  - arv_buffer_get_system_timestamp: the host's CLOCK_REALTIME (g_get_real_time, in us) when
//    the stream thread received the frame's leader. On our clock family, but late by a
//    varying delay (network, interrupt coalescing, scheduling) and stepped by NTP.
// CameraClockMapper combines them: the camera stamp for precision, the host stamp for the
// absolute position, via the lower envelope of (host - camera). The receipt is never before
// the stamped instant (causality), so the envelope is the least-delayed frames; latency
// spikes only lie above it and are ignored.
//
// What the camera stamps: GigE Vision/SFNC cameras typically latch the timestamp at frame
// start, i.e. the start of exposure of the first row (CameraStamp::ExposureStart); some latch
// at the end of exposure / start of readout (CameraStamp::ExposureEnd). ReceiptModel says how
// early the stamped instant is, at the least, before the host's receipt of the leader.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace rsd::drivers {

// Both host clocks at one instant, to move a CLOCK_REALTIME stamp onto CLOCK_MONOTONIC.
struct HostClocks {
  int64_t realtime_ns = 0;
  int64_t monotonic_ns = 0;
};
// One bracketing read: CLOCK_REALTIME between two reads of CLOCK_MONOTONIC.
struct ClockBracket {
  int64_t monotonic_before_ns = 0, realtime_ns = 0, monotonic_after_ns = 0;
};
// The realtime read on CLOCK_MONOTONIC, at the mid-point of the narrowest of `n` brackets (n >= 1).
// A thread preempted inside a bracket leaves its realtime read anywhere in it, the mid-point off
// by up to half the preemption; the camera clock's mapping follows the least receipt delay
// (CameraClockMapper), so one such read that moved a receipt earlier would move every later
// stamp earlier with it (by 70-100 us under ASan on a loaded two-core host).
HostClocks from_narrowest(const ClockBracket* brackets, size_t n);
// Up to eight brackets, stopping at the first within 2 us: from_narrowest of them.
HostClocks read_host_clocks();

// A stamp from the camera or Aravis (a guint64) through rsd's one check for times from outside
// (dsp::Stamp): 0, "no stamp", for one beyond its window, which the callers treat as absent.
int64_t checked_stamp(uint64_t raw);

// A host stamp on CLOCK_MONOTONIC. Aravis 0.8 stamps CLOCK_REALTIME; should a version stamp
// CLOCK_MONOTONIC instead, the clock whose "now" is nearer is taken. 0 (no stamp) gives
// `now.monotonic_ns`, the time of arrival in our hands.
int64_t host_stamp_to_monotonic(int64_t host_stamp_ns, const HostClocks& now);

enum class CameraStamp { ExposureStart, ExposureEnd };

// The least time from the instant the camera stamps to the host's receipt stamp, and the
// first row's exposure start from that instant.
struct ReceiptModel {
  CameraStamp stamp = CameraStamp::ExposureStart;
  double exposure_s = 0;
  // From the end of the first row's exposure (start of readout) to the host's receipt of the
  // frame's leader, at the least: ~0 for cameras that stream while reading out, the frame
  // readout for cameras that send a frame once it is whole; plus network latency.
  double leader_delay_s = 0;

  int64_t receipt_delay_ns() const;                     // stamped instant -> receipt
  int64_t first_row_ns(int64_t stamp_on_host_ns) const;  // stamped instant -> exposure start
};

// The rate fit's error is about the spread of the least delays divided by the span it sees:
// ~10 us / 5 s = 2 ppm for a hardware-stamping camera on a LAN, but Aravis' software fake
// camera, whose delays spread by ~200 us on a busy host, gives up to ~240 ppm over 2 s and
// 6..40 ppm over 4..15 s. Hence no rate until 5 s of frames, and a window well past that.
struct ClockMapperOptions {
  size_t window = 1024;           // recent frames the envelope is fitted to (34 s at 30 fps)
  double min_drift_span_s = 5.0;  // fit the rate only over at least this much camera time
  double max_drift = 200e-6;      // bound on |rate error| (crystals: within ~1e-4)
  double reset_below_s = 0.005;   // a frame this far below the envelope: camera clock jumped
  double reset_above_s = 1.0;     // ... or this far above it
};

// Maps camera-clock stamps to the host clock from pairs (camera stamp, host bound), where the
// host bound is never before the stamped instant. Fits the line host = camera + a + b (camera
// - mean) that lies under every pair of the window and is highest at the window's mean: the
// lower convex hull's edge over the mean (the linear program of Moon, Skelly and Towsley,
// "Estimation and removal of clock skew from network delay measurements", 1999), with b
// bounded by max_drift and fixed at 0 until the window spans min_drift_span_s. Stamps going
// backwards or far off the line restart the fit (camera reboot, clock reset). Memory is
// allocated once, at construction.
class CameraClockMapper {
 public:
  explicit CameraClockMapper(ClockMapperOptions opt = {});
  // Adds a frame and returns its camera stamp on the host clock.
  int64_t add(int64_t camera_ns, int64_t host_bound_ns);
  int64_t to_host(int64_t camera_ns) const;  // valid once add() was called
  double drift() const { return slope_; }    // host s per camera s, minus 1
  size_t size() const { return count_; }
  uint64_t resets() const { return resets_; }
  void clear();

 private:
  size_t index(size_t i) const { return (head_ + i) % x_.size(); }
  bool off_the_line(int64_t camera_ns, int64_t host_bound_ns) const;
  void refit();
  double hull_slope_at(double x);

  ClockMapperOptions opt_;
  std::vector<int64_t> x_, y_;  // ring: camera stamp, host bound minus camera stamp
  size_t head_ = 0, count_ = 0;
  std::vector<size_t> hull_;    // scratch for the lower hull, indices into the window
  int64_t x_ref_ = 0, y_ref_ = 0;
  double slope_ = 0, x_mean_ = 0, y_at_mean_ = 0;  // relative to x_ref_, y_ref_
  uint64_t resets_ = 0;
};

// The frame id as a counter that only grows. GigE Vision 1.x block ids are 16 bits and wrap
// from 65535 to 1 (0 is reserved); an id that falls elsewhere is a restart of the camera's
// counter (acquisition restarted, camera reset), which continues the count by one.
class FrameCounter {
 public:
  uint64_t next(uint64_t frame_id);
  uint64_t restarts() const { return restarts_; }

 private:
  bool started_ = false;
  uint64_t last_id_ = 0, count_ = 0, restarts_ = 0;
};

}  // namespace rsd::drivers
