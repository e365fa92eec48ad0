// recording-v1 on disk: what the simulator writes reads back bit for bit, and every kind of
// malformed file is refused with its file, line and column named.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "formats/recording_v1.hpp"
#include "formats/scenario_file.hpp"
#include "formats/yaml_map.hpp"
#include "dsp/sim/recording_simulation.hpp"

using namespace rsd;
namespace fs = std::filesystem;

namespace {

fs::path temp_dir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("rsd-test-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(p);
  return p;
}

dsp::SimulatedRecording small(dsp::ObservationKind kind) {
  dsp::SimConfig c;
  c.kind = kind;
  c.duration_s = 0.3;
  c.outlier_fraction = kind == dsp::ObservationKind::Matches ? 0.1 : 0.0;
  c.gyro.rate_min_hz = 20, c.gyro.rate_max_hz = 200, c.gyro.repeat_probability = 0.1;
  c.effects.time_offset_s = 0.01;
  return dsp::simulate_recording(c);
}

void replace_line(const fs::path& file, int line, const std::string& text) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  lines.at(line - 1) = text;
  std::ofstream out(file);
  for (const auto& l : lines) out << l << '\n';
}

std::string error_of(const fs::path& dir) {
  try {
    formats::read_recording(dir.string());
  } catch (const formats::RecordingError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(RecordingIo, LandmarksRoundTripExactly) {
  const auto sim = small(dsp::ObservationKind::Landmarks);
  const fs::path dir = temp_dir("lm");
  formats::write_recording(dir.string(), sim.rec);
  const dsp::Recording r = formats::read_recording(dir.string());
  ASSERT_EQ(r.observations.size(), sim.rec.observations.size());
  ASSERT_EQ(r.trajectory.size(), sim.rec.trajectory.size());
  for (size_t i = 0; i < r.observations.size(); ++i) EXPECT_EQ(r.observations[i].px, sim.rec.observations[i].px);
  EXPECT_EQ(r.trajectory[7].p, sim.rec.trajectory[7].p);
  EXPECT_EQ(r.trajectory[7].q.coeffs(), sim.rec.trajectory[7].q.coeffs());
  EXPECT_EQ(r.nominal.cam.fx, sim.rec.nominal.cam.fx);
  EXPECT_EQ(r.nominal.time.t0, sim.rec.frames.front().t);
  EXPECT_EQ(*r.noise_px, 0.5);
  fs::remove_all(dir);
}

TEST(RecordingIo, MatchesRoundTripWithRepeatedGyroStamps) {
  const auto sim = small(dsp::ObservationKind::Matches);
  const fs::path dir = temp_dir("mt");
  formats::write_recording(dir.string(), sim.rec);
  const dsp::Recording r = formats::read_recording(dir.string());
  ASSERT_EQ(r.matches.size(), sim.rec.matches.size());
  ASSERT_EQ(r.gyro.size(), sim.rec.gyro.size());
  EXPECT_EQ(r.matches.back().b, sim.rec.matches.back().b);
  EXPECT_EQ(r.gyro[3].w, sim.rec.gyro[3].w);
  EXPECT_EQ(r.motion, dsp::MotionKind::Gyro);
  fs::remove_all(dir);
}

TEST(RecordingIo, MalformedFilesAreNamedWithLineAndColumn) {
  const auto sim = small(dsp::ObservationKind::Landmarks);
  const fs::path dir = temp_dir("bad");
  auto fresh = [&] {
    fs::remove_all(dir);
    formats::write_recording(dir.string(), sim.rec);
  };
  fresh();
  replace_line(dir / "frames.csv", 3, "1,abc");
  EXPECT_NE(error_of(dir).find("frames.csv:3:3: field 't': 'abc' is not a finite number"), std::string::npos) << error_of(dir);
  fresh();  // a time beyond rsd's window for times from outside (dsp::Stamp: 2^61 ns, 2.3e9 s)
  replace_line(dir / "frames.csv", 3, "1,1e300");
  EXPECT_NE(error_of(dir).find("frames.csv:3:3: field 't': time 1e300 s is beyond +-"), std::string::npos) << error_of(dir);
  fresh();
  replace_line(dir / "trajectory.csv", 2, "-3e9,0,0,0,1,0,0,0");
  EXPECT_NE(error_of(dir).find("trajectory.csv:2:1: field 't': time -3e9 s is beyond +-"), std::string::npos) << error_of(dir);
  fresh();
  replace_line(dir / "observations.csv", 1, "frame,id,v,u");
  EXPECT_NE(error_of(dir).find("observations.csv:1:1: header is 'frame,id,v,u'"), std::string::npos) << error_of(dir);
  fresh();
  replace_line(dir / "observations.csv", 2, "0,99999,1,2");
  EXPECT_NE(error_of(dir).find("observations.csv:2:3: field 'id': point 99999 is not in points.csv"), std::string::npos)
      << error_of(dir);
  fresh();
  replace_line(dir / "trajectory.csv", 5, "1,2,3");
  EXPECT_NE(error_of(dir).find("trajectory.csv:5:1: expected 8 fields, found 3"), std::string::npos) << error_of(dir);
  fresh();
  fs::remove(dir / "points.csv");
  EXPECT_NE(error_of(dir).find("points.csv: cannot open"), std::string::npos) << error_of(dir);
  fresh();
  replace_line(dir / "recording.yaml", 1, "format: rsd-recording/2");
  EXPECT_NE(error_of(dir).find("recording.yaml:1:9: 'format' is 'rsd-recording/2', expected rsd-recording/1"), std::string::npos) << error_of(dir);
  fs::remove_all(dir);
}

TEST(Scenario, UnknownKeysAndBadValuesNameTheLine) {
  const fs::path dir = temp_dir("sc");
  fs::create_directories(dir);
  const fs::path f = dir / "s.yaml";
  auto err = [&](const std::string& text) {
    std::ofstream(f) << text;
    try {
      formats::load_scenario(f.string());
    } catch (const formats::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(err("seed: 1\ncamera: {width: 640, hieght: 480}\n").find("s.yaml:2:22: unknown key 'camera.hieght'"),
            std::string::npos);
  EXPECT_NE(err("timing:\n  frame_rate_hz: fast\n").find("s.yaml:2:18: 'timing.frame_rate_hz' must be a number"),
            std::string::npos);
  EXPECT_NE(err("effects:\n  wobble: {x: 1}\n").find("'effects.wobble' is not an effect of recording-v1"),
            std::string::npos);
  EXPECT_NE(err("effects:\n  time_offset: 0.01\n").find("'effects.time_offset' must be a mapping"), std::string::npos);
  EXPECT_EQ(err("effects:\n  time_offset: {time_offset_s: 0.01}\n"), "");
  // The lens: pinhole-radtan or pinhole-equi, and each one's own terms.
  EXPECT_NE(err("camera: {model: fisheye}\n").find("'camera.model' is 'fisheye': the lens models are pinhole-radtan and pinhole-equi"),
            std::string::npos) << err("camera: {model: fisheye}\n");
  EXPECT_EQ(err("camera: {model: pinhole-equi, distortion: [0.05, -0.01, 0.002, -0.0003]}\n"), "");
  // lens_model: a lens of the other family; lens_distortion: the nominal lens's own terms.
  EXPECT_EQ(err("effects:\n  lens_model: {model: pinhole-equi, k1: 0.05, k4: -0.001}\n"), "");
  EXPECT_NE(err("effects:\n  lens_model: {model: pinhole-radtan}\n").find("is the nominal lens's own family"), std::string::npos);
  EXPECT_NE(err("effects:\n  lens_model: {model: pinhole-equi}\n  lens_distortion: {k1: 0.1}\n")
                .find("'effects.lens_model' and lens_distortion together"),
            std::string::npos);
  EXPECT_NE(err("effects:\n  lens_distortion: {k1: 0.1, k3: 0.2}\n").find("unknown key 'effects.lens_distortion.k3'"),
            std::string::npos);  // a radtan nominal lens has no k3 here
  EXPECT_EQ(err("camera: {model: pinhole-equi}\neffects:\n  lens_distortion: {k1: 0.1, k3: 0.2}\n"), "");
  fs::remove_all(dir);
}

// recording-v1's camera.model: a fisheye nominal camera is written with its model and its
// k1..k4 and reads back bit for bit; a radtan one is written as before (no model key).
TEST(RecordingIo, AFisheyeNominalCameraRoundTrips) {
  auto sim = small(dsp::ObservationKind::Landmarks);
  sim.rec.nominal.cam.dist = dsp::Distortion::equidistant(0.0469, -0.0135, 0.0021, -1.0 / 3000);
  const fs::path dir = temp_dir("fish");
  formats::write_recording(dir.string(), sim.rec);
  const dsp::Recording r = formats::read_recording(dir.string());
  EXPECT_EQ(r.nominal.cam.dist, sim.rec.nominal.cam.dist);
  std::ifstream yaml(dir / "recording.yaml");
  const std::string text((std::istreambuf_iterator<char>(yaml)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("model: pinhole-equi"), std::string::npos) << text;
  fs::remove_all(dir);
  const auto plain = small(dsp::ObservationKind::Landmarks);
  formats::write_recording(dir.string(), plain.rec);
  std::ifstream yaml2(dir / "recording.yaml");
  const std::string text2((std::istreambuf_iterator<char>(yaml2)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text2.find("model:"), std::string::npos) << text2;
  EXPECT_EQ(formats::read_recording(dir.string()).nominal.cam.dist, plain.rec.nominal.cam.dist);
  fs::remove_all(dir);
}
