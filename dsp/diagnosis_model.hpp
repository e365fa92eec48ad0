// The recording's model with every effect parameter of ../shared/formats/recording-v1.md
// ("Named effects") in one vector, so that the diagnosis can free any subset of them and
// fit it. Residuals are observed minus predicted pixels; the prediction is the nominal
// model's own (dsp/observation_model.hpp), so a fit with nothing free reproduces the
// baseline exactly.
#pragma once

#include <Eigen/Core>
#include <array>
#include <bitset>
#include <optional>
#include <utility>
#include <vector>

#include "dsp/camera_motion.hpp"
#include "dsp/recording.hpp"

namespace rsd::dsp {

// The continuous parameters. Order is fixed; names are the spec's.
enum class Param : int { LineDelay, TimeOffset, Drift, K1, K2, Fx, Fy, LeverX, LeverY, LeverZ, Count };
constexpr int kParamCount = static_cast<int>(Param::Count);
using ParamMask = std::bitset<kParamCount>;

const char* param_name(Param p);

struct ModelParams {
  std::array<double, kParamCount> v{};
  bool flip_readout = false;  // readout_direction: the opposite of the nominal order
  double& operator[](Param p) { return v[static_cast<int>(p)]; }
  double operator[](Param p) const { return v[static_cast<int>(p)]; }
};

// The nominal model's values of every parameter (no effect switched on).
ModelParams nominal_params(const NominalModel& n);
// A typical size of a change of each parameter: the fit works in these units so that one
// step size suits all (a line delay of 1e-5 s and a focal length of 900 px alike).
double param_scale(Param p, const NominalModel& n);

// Landmarks recordings (motion kind trajectory). Matches are not modelled yet.
class DiagnosisModel {
 public:
  // Throws std::invalid_argument for a recording it cannot model (matches, no trajectory,
  // an observation naming an unknown frame or point).
  explicit DiagnosisModel(const Recording& rec);

  const Recording& recording() const { return rec_; }
  int size() const { return static_cast<int>(obs_.size()); }
  // Observed minus predicted pixel of observation i; nullopt when the model has no image
  // of the point (behind the camera, no rolling-shutter solution).
  std::optional<Eigen::Vector2d> residual(const ModelParams& p, int i) const;
  // Residuals of the observations `idx`; failed predictions are NaN.
  std::vector<Eigen::Vector2d> residuals(const ModelParams& p, const std::vector<int>& idx) const;
  // Position of observation i's frame in time order (0 = first frame).
  int frame_rank(int i) const { return obs_[i].rank; }
  double frame_time(int i) const { return obs_[i].T; }
  Eigen::Vector2d observed(int i) const { return obs_[i].px; }
  // Time offsets for which every frame stays inside the motion data.
  std::pair<double, double> offset_range() const;

 private:
  struct Obs {
    double T;
    int rank;
    Eigen::Vector3d X;
    Eigen::Vector2d px;
  };
  const Recording& rec_;
  SampledTrajectory body_;
  std::vector<Obs> obs_;
};

// The camera and time model that `p` describes.
LandmarkSetup landmark_setup(const NominalModel& n, const ModelParams& p);

}  // namespace rsd::dsp
