// A phone or logger's own text files: gyro samples as delimited columns in any order, and the
// frames' times one per line (docs/formats/sensor-csv.md). What rsd-extract reads when a rig
// leaves its pictures in a folder beside these two files. Errors throw std::runtime_error naming
// the file, the line and the column.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "dsp/observation/observation_model.hpp"

namespace rsd::formats {

// Where each quantity sits in a gyro line: "t,wx,wy,wz" (the default), "wx,wy,wz,t", or with
// "-" for columns to skip ("t,-,-,wx,wy,wz"). Columns are 0-based.
struct GyroColumns {
  std::array<int, 4> index{0, 1, 2, 3};  // of t, wx, wy, wz
  int count = 4;                          // columns the spec names (a line needs at least these)
  std::string spec = "t,wx,wy,wz";
};
// Throws std::invalid_argument naming what is wrong ("'wq' is not t, wx, wy, wz or -").
GyroColumns parse_gyro_columns(const std::string& spec);

// Seconds per unit of a time column: "s", "ms", "us" or "ns"; std::invalid_argument otherwise.
double time_unit_seconds(const std::string& unit);

// Gyro samples (rad/s; t in seconds after multiplying by unit_s). Fields are separated by commas,
// semicolons, tabs or spaces; a first line that is not numbers is a header and skipped, as are
// blank lines and lines starting with '#'. Sample times must not decrease; at least two samples.
std::vector<dsp::GyroSample> read_gyro_csv(const std::string& path, const GyroColumns& columns, double unit_s);

// Frame times (seconds after multiplying by unit_s): the first field of every line, frame k on
// the k-th such line (from 0); they must increase. Header, blank and '#' lines as above.
std::vector<double> read_frame_times(const std::string& path, double unit_s);

}  // namespace rsd::formats
