// Pictures to observations: features tracked between consecutive frames (matches, for a gyro)
// or a known target's corners detected in every frame (landmarks, for a trajectory). The one
// path by which rsd-extract (from an LCM log or an images recording) and rsd-diagnose (from
// an images recording) make observations, so that both see the same ones.
#pragma once

#include <opencv2/core.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "dsp/core/image.hpp"
#include "dsp/features/feature_tracks.hpp"
#include "dsp/observation/recording.hpp"
#include "dsp/sim/calibration_target.hpp"
#include "formats/recording_v1.hpp"

namespace rsd::tools {

struct PictureFrames {
  std::function<std::optional<dsp::Image>()> next;  // the next picture, in frame order
  std::vector<int> numbers;                          // each picture's frame number
  std::vector<double> times;                         // each picture's stamp (camera clock)
  std::vector<bool> usable;                          // whether the motion covers its readout
  std::string what;                                  // for messages: the log or the recording
};

// Frames whose whole readout the motion spans at the nominal time offset, with `margin_s` to
// spare either side: outside it the motion would be extrapolated, and a diagnosis would blame
// the camera for it; the margin leaves the diagnosis room to find a clock offset of up to that
// much (its bounds keep every frame's motion inside the data).
inline constexpr double kMotionMarginS = 0.05;
std::vector<bool> covered_by_motion(const std::vector<double>& frame_t, double motion_t0, double motion_t1,
                                    const dsp::NominalModel& nominal, double margin_s = kMotionMarginS);

// 8-bit grey for tracking and detection; 16-bit pictures are scaled by one factor for the
// whole sequence (from the first frame's maximum: tracking assumes constant brightness).
cv::Mat grey8(const dsp::Image& img, double& scale16);

// Frame pairs tracked at most by default (rsd-extract and rsd-diagnose --track-pairs): 240 pairs
// of up to 300 matches (dsp::TrackOptions::max_per_pair) offer the diagnosis's fits, which see
// at most 30 000 observations (rsd-diagnose --fit-observations), twice what they take; a minute
// at 30 fps has 1799.
inline constexpr size_t kTrackedPairs = 240;
inline constexpr const char* kTrackPairsHelp =
    "matches kind: track at most this many frame pairs, chosen by the gyro's rates and evenly over the recording "
    "(0: every pair; more is slower, rarely better)";

// Appends the matches between consecutive usable frames to rec.matches: every such pair when
// there are at most `max_pairs` (0: no limit), else that many chosen by the gyro's rates
// (dsp::choose_frame_pairs), and rec.frames keeps only the frames of tracked pairs. Prints a
// summary. Throws std::runtime_error when nothing could be tracked.
void make_matches(PictureFrames& frames, const dsp::TrackOptions& opt, dsp::Recording& rec, size_t max_pairs = kTrackedPairs);
// Appends the target's corners seen in usable frames to rec.observations and sets rec.points.
// Throws std::runtime_error when the target is nowhere.
void make_landmarks(PictureFrames& frames, const dsp::TargetSpec& target, const std::string& target_name,
                    dsp::Recording& rec);

// An images recording with its observations made from its pictures: matches with a gyro,
// landmarks of its target with a trajectory. Frames the motion does not cover are left out.
// `max_pairs` as for make_matches.
dsp::Recording observations_from_pictures(const formats::ImagesRecording& r, const dsp::TrackOptions& opt,
                                          size_t max_pairs = kTrackedPairs);

}  // namespace rsd::tools
