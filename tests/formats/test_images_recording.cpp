// Images recordings (observations.kind: images): the header, frames, motion and pictures read
// back as written; every way the pictures' list can be wrong is refused naming the file, line
// or key; and a recording with observations is not mistaken for one with pictures.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "formats/image_file.hpp"
#include "formats/recording_v1.hpp"
#include "formats/video_file.hpp"
#include "tests/support/temp_dir.hpp"

using namespace rsd;
namespace fs = std::filesystem;

namespace test_images_recording {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

// The test's directories, inside one of this process's that goes when it ends.
const rsd::test::TempDir& g_tmp = rsd::test::register_temp_dir("rsd-test-images-");

fs::path temp_dir(const std::string& name) {
  const fs::path p = g_tmp.path(name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

// Three frames of a gyro recording, their pictures as PNG files in dir/frames.
formats::ImagesRecording three_frames(const fs::path& dir) {
  formats::ImagesRecording r;
  r.rec.kind = dsp::ObservationKind::Matches;
  r.rec.motion = dsp::MotionKind::Gyro;
  r.rec.nominal.cam.width = 8, r.rec.nominal.cam.height = 6;
  r.rec.nominal.cam.fx = r.rec.nominal.cam.fy = 10, r.rec.nominal.cam.cx = 3.5, r.rec.nominal.cam.cy = 2.5;
  r.rec.nominal.time.line_delay_s = 1e-3;
  for (int k = 0; k < 3; ++k) r.rec.frames.push_back({10 + k, 0.1 * k});
  for (int k = 0; k < 10; ++k) r.rec.gyro.push_back({0.03 * k, {0.1, 0.2, 0.3}});
  fs::create_directories(dir / "frames");
  for (int k = 0; k < 3; ++k) {
    dsp::Image img(8, 6, dsp::PixelFormat::Mono8);
    img.data.assign(img.data.size(), static_cast<uint8_t>(40 * k));
    const std::string f = (dir / "frames" / ("f" + std::to_string(k) + ".png")).string();
    formats::write_png(f, img.view());
    r.files.push_back(f);
  }
  return r;
}

std::string error_of(const fs::path& dir) {
  try {
    formats::read_images_recording(dir.string());
  } catch (const formats::RecordingError& e) {
    return e.what();
  }
  return "";
}

void append(const fs::path& file, const std::string& text) { std::ofstream(file, std::ios::app) << text; }

}  // namespace

TEST(ImagesRecording, RoundTripsWithPicturesInFrameOrder) {
  const fs::path dir = temp_dir("rt");
  formats::write_images_recording(dir.string(), three_frames(dir));
  EXPECT_TRUE(formats::is_images_recording(dir.string()));
  const formats::ImagesRecording r = formats::read_images_recording(dir.string());
  EXPECT_EQ(r.rec.kind, dsp::ObservationKind::Matches);  // what pictures with a gyro make
  ASSERT_EQ(r.rec.frames.size(), 3u);
  ASSERT_EQ(r.files.size(), 3u);
  EXPECT_EQ(r.rec.frames[1].frame, 11);
  EXPECT_EQ(fs::path(r.files[1]).filename(), "f1.png");
  EXPECT_EQ(formats::read_image(r.files[2]).data[0], 80);  // the path resolves from here
  EXPECT_EQ(r.rec.gyro.size(), 10u);
  EXPECT_DOUBLE_EQ(r.rec.nominal.time.line_delay_s, 1e-3);
  // Relative to the directory in the file, so the recording can move.
  std::ifstream csv(dir / "images.csv");
  std::string header, first;
  std::getline(csv, header), std::getline(csv, first);
  EXPECT_EQ(header, "frame,file");
  EXPECT_EQ(first, "10,frames/f0.png");
}

TEST(ImagesRecording, ObservationReadersRefuseIt) {
  const fs::path dir = temp_dir("refuse");
  formats::write_images_recording(dir.string(), three_frames(dir));
  try {
    formats::read_recording(dir.string());
    FAIL() << "an images recording read as observations";
  } catch (const formats::RecordingError& e) {
    EXPECT_NE(std::string(e.what()).find("observations.kind is images"), std::string::npos) << e.what();
  }
}

TEST(ImagesRecording, BadPictureListsAreNamed) {
  const fs::path dir = temp_dir("bad");
  formats::write_images_recording(dir.string(), three_frames(dir));
  append(dir / "images.csv", "99,frames/f0.png\n");
  EXPECT_NE(error_of(dir).find("images.csv:5:1: field 'frame': frame 99 is not in frames.csv"), std::string::npos) << error_of(dir);

  formats::write_images_recording(dir.string(), three_frames(dir));
  append(dir / "images.csv", "11,frames/f1.png\n");
  EXPECT_NE(error_of(dir).find("images.csv:5:1: field 'frame': frame 11 appears twice"), std::string::npos) << error_of(dir);

  formats::write_images_recording(dir.string(), three_frames(dir));
  append(dir / "frames.csv", "13,0.3\n");
  EXPECT_NE(error_of(dir).find("images.csv: frame 13 of frames.csv has no picture"), std::string::npos) << error_of(dir);
}

TEST(ImagesRecording, HeaderMistakesAreNamed) {
  const fs::path dir = temp_dir("header");
  formats::write_images_recording(dir.string(), three_frames(dir));
  std::ifstream in(dir / "recording.yaml");
  const std::string yaml((std::istreambuf_iterator<char>(in)), {});
  in.close();
  using Edit = std::pair<std::string, std::string>;
  auto with = [&](std::initializer_list<Edit> edits) {
    std::string y = yaml;
    for (const Edit& e : edits) {
      const size_t at = y.find(e.first);
      EXPECT_NE(at, std::string::npos) << e.first;
      if (at != std::string::npos) y.replace(at, e.first.size(), e.second);
    }
    std::ofstream(dir / "recording.yaml") << y;
    return error_of(dir);
  };
  EXPECT_NE(with({{"file: images.csv", "file: images.csv\n  video: capture.mp4"}}).find("either file (images.csv) or video"),
            std::string::npos);
  EXPECT_NE(with({{"file: images.csv", "video: missing.mp4"}}).find("missing.mp4 does not exist"), std::string::npos);
  EXPECT_NE(with({{"file: images.csv", "file: images.csv\n  target: {type: checkerboard, cols: 5, rows: 4, square_m: 0.05}"}})
                .find("'observations.target' applies to images recordings with trajectory motion only"),
            std::string::npos);
  // Pictures with a trajectory need the target to detect and its points.
  std::ofstream(dir / "trajectory.csv") << "t,x,y,z,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n1,0,0,0,1,0,0,0\n";
  std::ofstream(dir / "points.csv") << "id,x,y,z\n0,0,0,0\n";
  const Edit trajectory{"kind: gyro\n  file: gyro.csv", "kind: trajectory\n  file: trajectory.csv"};
  EXPECT_NE(with({trajectory}).find("'observations.points' is missing"), std::string::npos) << with({trajectory});
  EXPECT_NE(with({trajectory, {"file: images.csv", "file: images.csv\n  points: points.csv"}}).find("'observations.target' is missing"),
            std::string::npos);
  // A square board's orientation is ambiguous: refused as the command line's --target is.
  const std::string square =
      with({trajectory, {"file: images.csv", "file: images.csv\n  points: points.csv\n  target: {type: checkerboard, cols: 4, rows: 4, square_m: 0.05}"}});
  EXPECT_NE(square.find("observations.target.type"), std::string::npos) << square;
  EXPECT_NE(square.find("differ"), std::string::npos) << square;
  EXPECT_EQ(with({trajectory, {"file: images.csv", "file: images.csv\n  points: points.csv\n  target: {type: checkerboard, cols: 5, rows: 4, square_m: 0.05}"}}),
            "");
}

TEST(ImagesRecording, TrajectoryWithTargetReadsItsPoints) {
  const fs::path dir = temp_dir("target");
  formats::ImagesRecording r = three_frames(dir);
  r.rec.kind = dsp::ObservationKind::Landmarks;
  r.rec.motion = dsp::MotionKind::Trajectory;
  r.rec.trajectory = {{0, {0, 0, 0}, Eigen::Quaterniond::Identity()}, {1, {0, 0, 0}, Eigen::Quaterniond::Identity()}};
  r.rec.points = {{0, {0, 0, 0}}, {1, {0.05, 0, 0}}};
  dsp::TargetSpec t;
  t.kind = dsp::TargetKind::Checkerboard, t.cols = 5, t.rows = 4, t.spacing_m = 0.05;
  r.target = t;
  formats::write_images_recording(dir.string(), r);
  const formats::ImagesRecording back = formats::read_images_recording(dir.string());
  EXPECT_EQ(back.rec.kind, dsp::ObservationKind::Landmarks);
  ASSERT_TRUE(back.target.has_value());
  EXPECT_EQ(back.target->cols, 5);
  EXPECT_EQ(back.target->rows, 4);
  EXPECT_DOUBLE_EQ(back.target->spacing_m, 0.05);
  EXPECT_EQ(back.rec.points.size(), 2u);
}

TEST(VideoFile, WrittenFramesReadBackInOrder) {
  const fs::path dir = temp_dir("video");
  const std::string path = (dir / "v.avi").string();
  {
    formats::VideoWriter w(path, 64, 48, 30);
    for (int k = 0; k < 5; ++k) {
      dsp::Image img(64, 48, dsp::PixelFormat::Mono8);
      img.data.assign(img.data.size(), static_cast<uint8_t>(30 + 40 * k));
      w.write(img.view());
    }
  }
  formats::VideoReader r(path);
  EXPECT_EQ(r.width(), 64);
  EXPECT_EQ(r.height(), 48);
  dsp::Image img;
  int k = 0;
  while (r.next(img)) {
    ASSERT_EQ(img.format, dsp::PixelFormat::Rgb8);
    // Motion-JPEG is lossy, but a flat grey frame stays within a few levels.
    EXPECT_NEAR(img.data[3 * (24 * 64 + 32)], 30 + 40 * k, 4) << "frame " << k;
    ++k;
  }
  EXPECT_EQ(k, 5);
  EXPECT_THROW(formats::VideoReader((dir / "none.mp4").string()), std::runtime_error);
  EXPECT_THROW(formats::VideoWriter((dir / "x.gif").string(), 64, 48, 30), std::runtime_error);
}

}  // namespace test_images_recording
