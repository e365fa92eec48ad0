// GoPro's GPMF metadata, the gyro of one payload (docs/formats/gpmf.md): the KLV layout GoPro
// publishes for the metadata track of its cameras' MP4 files. One payload (one sample of the MP4's
// `gpmd` track, about a second) holds devices (DEVC), each holding streams (STRM) of sensor data;
// the gyro stream's GYRO samples, divided by its SCAL, are rad/s in the axis order ORIN names.
//
// Layout: a key of four 7-bit ASCII characters, a type character, a structure size (bytes per
// sample, 8 bits), a repeat count (samples, 16 bits big-endian), then structure size x repeat
// bytes of big-endian data padded to a multiple of four; type 0 holds nested KLV items.
//
// The reader checks every length against the bytes that hold it and refuses, naming the byte
// offset and the key, what it cannot read: a length past the payload, nesting deeper than GPMF
// has, a gyro sample of other than three axes, a scale of zero. What it does not know (other
// streams, other keys) it skips. Not thread-safe to share a result while it is being filled.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rsd::formats {

// One gyro stream of one payload.
struct GpmfGyro {
  // The samples in rad/s, in the order the stream stores its axes (`orin`, e.g. "ZXY").
  std::vector<Eigen::Vector3d> rate_rad_s;
  std::string orin;                   // ORIN ("" when the stream has none: HERO5-7 document theirs)
  std::string device;                 // DVNM of the device holding the stream ("" when absent)
  std::optional<std::uint64_t> stmp_us;  // STMP: the first sample's time, microseconds
  std::optional<std::uint32_t> tsmp;     // TSMP: samples delivered since the recording started
  std::string siun;                   // SIUN as written ("rad/s"; "" when absent)
};

// A payload's gyro streams (most cameras have one). Throws std::runtime_error naming `what`
// (the file and the payload's index, say), the byte offset and the key on bad input.
std::vector<GpmfGyro> read_gpmf_gyro(const std::uint8_t* data, std::size_t size, const std::string& what);

}  // namespace rsd::formats
