// The blocked-halves check of the selection (select.hpp): an effect must hold out of the half of
// the recording it was fitted on, split in time and (gyro recordings) by angular rate. A stand-in
// for physics outside the table (a clock that jumps, a gyro that clips) fits one half's structure
// and mispredicts the other's, or puts its value where the other half does not.
#pragma once

#include <optional>
#include <vector>

#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/uncertainty.hpp"

namespace rsd::dsp {

// Two halves of some observations, split at the median of a key.
struct Halves {
  std::vector<int> a, b;
  bool usable() const { return a.size() >= 50 && b.size() >= 50; }
};
// Split by the frame's time.
Halves time_halves(const DiagnosisModel& m, const std::vector<int>& idx);
// Split by the gyro's angular rate (magnitude) nearest each observation's frame, on the motion
// clock of `p`.
Halves rate_halves(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p);

// A hypothesis: its parameters and which of them are free.
struct Hypothesis {
  ModelParams params;
  ParamMask free;
};

struct HalvesVerdict {
  // The robust chi-square drop from `poorer` to `richer` on the unseen half, plus the margin its
  // noise allows, in the worse direction (positive: it holds).
  double drop = 0;
  // How far apart the two halves put the parameters `richer` adds, in combined sigmas (the
  // largest; 0 where a half cannot measure them). A lens's radial terms are compared as the
  // curve they draw within the image's field, not term by term (terms of one lens trade).
  double apart_sigmas = 0;
};
// A hypothesis fitted on each half: on[0] on h.a, on[1] on h.b.
struct HalvesFits {
  ModelParams on[2];
};
HalvesFits fit_halves(const DiagnosisModel& m, const Halves& h, const Hypothesis& hyp, double sigma, int iterations);
// The richer hypothesis's fits with each one's parameter covariance over the hypothesis's free
// parameters, clustered by blocks of kHalvesBlockS (empty where a half cannot measure them).
struct CovariedHalves {
  HalvesFits fits;
  std::optional<ParameterCovariance> cov[2];
};
CovariedHalves with_covariances(const DiagnosisModel& m, const Halves& h, const ParamMask& free, const HalvesFits& fits);

// The robust chi-square drop from residuals r0 to r1 plus three standard errors of it, taken
// from the spread of the drop's shares in the blocks the observations fall in (`block[k]`:
// observation k's): a drop that one or two blocks' structure decides is within its margin, one
// that block after block shows is not. Minus infinity with fewer than kMinClusters blocks.
double block_margined_drop(const std::vector<int>& block, const std::vector<Eigen::Vector2d>& r0,
                           const std::vector<Eigen::Vector2d>& r1, double sigma);

// Judges the two hypotheses, each fitted on both halves, each fit on the half it did not see:
// the richer must predict it no worse than the poorer beyond the larger of the noise's margin
// and block_margined_drop's, on the whole half or its bulk. A fit on a weak half (each value the
// richer adds measured there with kWeakHalfSigmas times the other half's sigma) is not asked to
// predict the strong half; it must agree with it (apart_sigmas).
HalvesVerdict cross_check(const DiagnosisModel& m, const Halves& h, const HalvesFits& poorer, const ParamMask& poorer_free,
                          const HalvesFits& richer, const ParamMask& richer_free, double sigma);
// The same with the richer fits' covariances known: a selection judges every named effect
// against the same richer fits, whose covariances are then computed once, not once an effect (a
// second of the walking phone's minute, five effects).
HalvesVerdict cross_check(const DiagnosisModel& m, const Halves& h, const HalvesFits& poorer, const ParamMask& poorer_free,
                          const CovariedHalves& richer, const ParamMask& richer_free, double sigma);
// Fits both hypotheses on each half (at most `iterations`), judges them on the other.
HalvesVerdict cross_check(const DiagnosisModel& m, const Halves& h, const Hypothesis& poorer, const Hypothesis& richer,
                          double sigma, int iterations);

// Beyond this many combined sigmas apart, the two halves disagree on an effect's value. The
// sigmas are clustered by blocks of kHalvesBlockS; a half with fewer than 20 blocks (a recording
// under about 10 s) has no say on the value.
inline constexpr double kHalvesAgreeSigmas = 4.0;
// No sigma of that test is below this fraction of the value's distance from the poorer
// hypothesis's: halves that agree on an effect to a tenth of its size agree on the effect.
inline constexpr double kHalvesSizeFraction = 0.1;
inline constexpr double kHalvesBlockS = 0.25;
// A half whose sigma on every value the richer hypothesis adds is at least this many times the
// other half's (a ninth of its information) shows the effect weakly (issue 34, point 3).
inline constexpr double kWeakHalfSigmas = 3.0;

}  // namespace rsd::dsp
