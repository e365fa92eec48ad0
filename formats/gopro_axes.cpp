#include "formats/gopro_axes.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

namespace rsd::formats {

namespace {

// GoPro's body axes in rsd's camera frame, column k the body's axis k: X (to the left as the
// picture shows it) is -x, Y (out of the back) is -z, Z (up) is -y.
Eigen::Matrix3d body_to_camera() {
  Eigen::Matrix3d b;
  b << -1, 0, 0,  //
      0, 0, -1,   //
      0, -1, 0;
  return b;
}

// The models without ORIN and the order GoPro documents for their GYRO (its GPMF parser's
// README): a firmware string starts with the model's code.
struct Documented {
  const char* firmware_prefix;
  const char* model;
  const char* letters;
};
constexpr Documented kDocumented[] = {
    {"HD5.", "HERO5 Black", "ZXY"},
    {"HD6.", "HERO6 Black", "YxZ"},
};

}  // namespace

std::optional<Eigen::Matrix3d> gopro_letters_to_camera(const std::string& letters) {
  if (letters.size() != 3) return std::nullopt;
  // rows: channel i = sign * body axis
  Eigen::Matrix3d channels = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) {
    const char c = letters[static_cast<size_t>(i)];
    const int axis = (c >= 'X' && c <= 'Z') ? c - 'X' : (c >= 'x' && c <= 'z') ? c - 'x' : -1;
    if (axis < 0 || channels.col(axis).any()) return std::nullopt;  // not an axis, or one named twice
    channels(i, axis) = (c >= 'X' && c <= 'Z') ? 1.0 : -1.0;
  }
  // A mirror is no gyro: its channels would be a left-handed frame.
  if (channels.determinant() < 0) return std::nullopt;
  // sample = channels * w_body and w_body = body_to_camera^T w_camera, so
  // w_camera = body_to_camera * channels^T * sample.
  return body_to_camera() * channels.transpose();
}

std::optional<GoProAxes> gopro_axes(const std::string& orin, const std::string& firmware) {
  if (!orin.empty()) {
    const auto m = gopro_letters_to_camera(orin);
    if (!m)
      throw std::invalid_argument("the gyro's ORIN '" + orin + "' is not three different axes of X, Y, Z (lower case: negative) "
                                  "forming a right-handed frame");
    return GoProAxes{*m, orin, "the gyro's ORIN '" + orin + "'"};
  }
  for (const Documented& d : kDocumented)
    if (firmware.rfind(d.firmware_prefix, 0) == 0)
      return GoProAxes{*gopro_letters_to_camera(d.letters), d.letters,
                       std::string("the order GoPro documents for the ") + d.model + " (firmware " + firmware + ")"};
  return std::nullopt;
}

}  // namespace rsd::formats
