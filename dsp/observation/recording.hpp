// An observation recording (docs/formats/recording-v1.md) in memory: what the files say,
// nothing more. Reading and writing the files is the tools' job.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "dsp/geometry/camera_model.hpp"
#include "dsp/observation/observation_model.hpp"

namespace rsd::dsp {

enum class ObservationKind { Landmarks, Matches };
enum class MotionKind { Trajectory, Gyro };

// What the recording's header (the "simulation") says: the nominal model.
struct NominalModel {
  CameraModel cam;  // its lens: pinhole-radtan k1, k2, p1, p2 (the spec has no k3) or pinhole-equi k1..k4
  double frame_rate_hz = 30;
  TimeModel time;   // line delay, readout, offset, drift; t0 = first frame's timestamp
  Eigen::Matrix3d imu_to_camera = Eigen::Matrix3d::Identity();
  Eigen::Vector3d lever_arm = Eigen::Vector3d::Zero();
};

struct FrameStamp {
  int frame;
  double t;  // camera clock: capture time of the first row read
};
struct PoseSample {
  double t;  // motion clock
  Eigen::Vector3d p;
  Eigen::Quaterniond q;  // world-from-body
};
struct Landmark {
  int id;
  Eigen::Vector3d X;
};
struct LandmarkObservation {
  int frame, id;
  Eigen::Vector2d px;
};
struct Match {
  int frame_a;
  Eigen::Vector2d a;
  int frame_b;
  Eigen::Vector2d b;
};

struct Recording {
  ObservationKind kind = ObservationKind::Landmarks;
  MotionKind motion = MotionKind::Trajectory;
  NominalModel nominal;
  std::vector<FrameStamp> frames;
  std::vector<PoseSample> trajectory;  // motion kind trajectory
  std::vector<GyroSample> gyro;        // motion kind gyro
  std::vector<Landmark> points;        // landmarks
  std::vector<LandmarkObservation> observations;  // landmarks
  std::vector<Match> matches;          // matches
  std::optional<double> noise_px;
};

const char* to_string(ObservationKind k);
const char* to_string(MotionKind k);

}  // namespace rsd::dsp
