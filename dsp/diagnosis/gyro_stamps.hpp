// The gyro samples' times estimated from their rates. A gyro's stamps are often the host's
// arrival times, off the sensor's sampling by a jitter of a fraction of a millisecond; a rate
// placed at the wrong time turns the integrated orientation by the rate's change over the error
// (w' x dt: 14 rad/s^2 of a hand's shake and 0.5 ms of jitter give 7 mrad/s, 0.2 mrad over a
// frame pair). That error is independent from pair to pair: under the translation nuisance,
// whose smooth velocity absorbs the rotation's slow part but not it, it pulled a walking phone's
// focal length 0.5% low on every seed (docs/diagnosis.md, "Gyro timestamp jitter").
//
// Where the rate changes fast the stamps are held by the rates themselves: a sample off the
// curve through its neighbours along that curve's slope, by more than the noise that moves it
// across the slope too, was taken earlier or later than stamped. The rates are first scaled to
// equal noise on every axis, and the jitter's spread is measured from that excess over the
// whole recording, on slopes clear of their own noise; the times are then those that best
// explain the rates and the stamps together under that spread (nothing moves when the excess
// is within the noise: a gyro sampled on time keeps its stamps).
//
// Thread contract: a pure function.
#pragma once

#include <vector>

#include "dsp/observation/observation_model.hpp"

namespace rsd::dsp {

// What the rates said of the stamps.
struct StampSpread {
  double jitter_s = 0;     // the stamps' spread the rates show (RMS), 0 if none shows
  double moved_rms_s = 0;  // RMS of the moves applied (0: the stamps kept)
};

struct GyroStamps {
  std::vector<GyroSample> gyro;  // as given, each t the estimated sampling time
  StampSpread spread;
};

// `gyro` as clean_gyro returns it (sorted, times strictly increasing). Samples with a gap
// (an interval over `max_interval`) among their two neighbours on either side keep their
// stamps, and no sample moves past the middle of either interval beside it, so the order holds.
GyroStamps estimate_gyro_stamps(const std::vector<GyroSample>& gyro, double max_interval);

}  // namespace rsd::dsp
