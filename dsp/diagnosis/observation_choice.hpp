// Which observations the diagnosis fits on when a recording has more than it needs (issue 34,
// point 5: a minute of 1080p in 20 s, ten minutes in 3 minutes). The cost of every fit grows with
// the observations it sees; the information about the model's parameters does not grow alike:
// the matches of a frame pair share its gyro noise and stamp jitter, so past a few dozen a pair's
// matches add little, and a frame in which nothing moves tells the fit nothing of the readout,
// the clock offset or the gyro's scale. So frames (frame pairs) are chosen by the information
// they carry about the parameters of every applicable effect, the sum of their observations'
// statistical leverage in the linearised fit, h_i = tr(J_i (J^T J)^+ J_i^T) (J_i the 2 x k
// Jacobian of observation i's residual), mixed half and half with an even share so that no part
// of the recording is left out (a fit that sees only the informative frames cannot notice
// physics outside the table elsewhere). Within a chosen frame the observations are an even
// share, not the highest leverage: leverage is highest at the image's rim, where a guessed lens
// is most wrong, and a fit on the rim alone carried that error into the clock offset (the Karma
// clip). A chosen frame keeps enough observations for the per-pair translation of the parallax
// nuisance (parallax.hpp) and for the frame-clustered uncertainty. Deterministic (systematic
// sampling, no random numbers).
#pragma once

#include <cstddef>
#include <vector>

#include "dsp/diagnosis/model.hpp"
#include "dsp/observation/observation_model.hpp"

namespace rsd::dsp {

struct ObservationChoice {
  size_t budget = 0;            // at most this many observations (0: all)
  size_t per_frame_min = 12;    // a chosen frame keeps at least this many (when it has them)
  size_t leverage_pool = 2;     // frames are chosen from a pool of this many times as many, evenly spread
  // Frames are chosen in runs of this many consecutive ones (1: each on its own). The translation
  // nuisance's velocity spline needs its pairs close in time: frames chosen one by one over ten
  // minutes are four pairs a second, too few for knots that follow a hand's shake.
  size_t run = 1;
};

// At most `choice.budget` of `idx` (DiagnosisModel order, ascending): frames (in runs of
// `choice.run` consecutive ones) by the leverage of their observations for the parameters in
// `mask` at `at`, an even share within each. `idx`
// itself when it is within the budget. The result is in ascending order.
std::vector<int> choose_observations(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& at,
                                     const ParamMask& mask, const ObservationChoice& choice);

// A matches recording's frames are chosen in runs of this many consecutive pairs (about a second
// at 30 fps, a fifth held out) when the budget leaves frames out (past about 100 s at 30 fps):
// chosen one by one they spread thinly (ten minutes: four pairs a second), and the translation
// nuisance's spline, which needs two pairs a knot interval, could then not follow a hand's shake
// (0.5 s knots: the ten-minute walk lost its lens and its focal length went 1% off); the
// remainder's tests, which compare each frame with the next, need them too. Within a run the
// pairs are as dense as the recording's.
inline constexpr size_t kMatchesRunFrames = 24;

// Whole runs of `run` consecutive frames of `idx` (DiagnosisModel order), `runs` of them evenly over
// the recording, `per_frame` of each frame's observations (an even share); ascending. For what
// needs each frame's neighbours in time and several observations a frame (the remainder's tests).
std::vector<int> evenly_in_runs(const DiagnosisModel& m, const std::vector<int>& idx, size_t runs, size_t run,
                                size_t per_frame);

// Leverage of each observation of `idx` for the parameters in `mask` at `at` (sum = the rank of
// the information, at most the number of free parameters). A failed prediction has none.
std::vector<double> observation_leverage(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& at,
                                         const ParamMask& mask);

// Before any picture is tracked: which consecutive frame pairs to track when a recording has
// more than `count` (tracking a 1080p pair costs several times what fitting its matches does).
// Pairs by what the gyro says they will carry: the squared mean rate over the pair (the readout,
// the focal length and the gyro's scale show in proportion to the rotation) plus the squared
// change of rate across it (the clock offset shows where the rate changes), each relative to its
// mean over the recording, mixed half and half with an even share as above. `frame_t`: the
// frames' stamps (camera clock); `usable[k]`: frame k's readout lies within the motion;
// `motion_offset_s`: t_motion = t_camera + offset. Returns chosen[k] for the pair (k-1, k)
// (chosen[0] false): every pair of two usable frames when there are at most `count` (0: all).
// Without gyro samples in a pair's span its information is nil (the even share still reaches it).
std::vector<bool> choose_frame_pairs(const std::vector<double>& frame_t, const std::vector<bool>& usable,
                                     const std::vector<GyroSample>& gyro, double motion_offset_s, size_t count);

// `count` of the items with inclusion weights `w` (non-negative), by systematic sampling on
// inclusion probabilities proportional to w, capped at 1 (an item of high weight is taken
// once): item k is taken with probability min(1, c w_k) for the c that makes them sum to count.
// Indices into w, ascending; all of them when count >= w.size().
std::vector<size_t> systematic_choice(const std::vector<double>& w, size_t count);

}  // namespace rsd::dsp
