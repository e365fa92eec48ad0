// A GoPro gyro's axes in rsd's camera frame (docs/formats/gpmf.md, "The gyro's axes"): from the
// stream's ORIN when the camera writes one, else from the order GoPro documents for the model
// the MP4's firmware string names (HERO5 Black, HERO6 Black). Pure: no I/O.
//
// GoPro names its axes on the camera's body (X to the camera's left as its picture shows it,
// Y out of its back, Z up) and says, per channel of a GYRO sample, which of them it measures,
// a lower-case letter for the negative axis: "ZXY" (the HERO5: channel 0 is Z), "YxZ" (the
// HERO6: Y, -X, Z), "XzY" (a MAX's ORIN). rsd's camera frame is x right, y down, z forward.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>

namespace rsd::formats {

struct GoProAxes {
  Eigen::Matrix3d imu_to_camera;  // w_camera = imu_to_camera * w_gyro (motion.imu_to_camera)
  std::string letters;            // GoPro's order of the channels, e.g. "ZXY"
  std::string source;             // where it came from, for the user: "ORIN 'XzY'", "documented for the HERO5 Black (firmware HD5...)"
};

// The rotation taking a gyro sample whose channels are `letters` (three of X Y Z x y z, each
// axis once, right-handed) into rsd's camera frame; nullopt when `letters` is not such a triple.
std::optional<Eigen::Matrix3d> gopro_letters_to_camera(const std::string& letters);

// The axes of a clip's gyro: its ORIN if not empty, else the documented order of the model
// `firmware` names (the MP4's `firmware` tag: "HD5." a HERO5 Black, "HD6." a HERO6 Black);
// nullopt when neither says (rsd-diagnose --imu-axes search asks the pictures then). Throws
// std::invalid_argument naming the ORIN when it is not a right-handed triple of axes.
std::optional<GoProAxes> gopro_axes(const std::string& orin, const std::string& firmware);

}  // namespace rsd::formats
