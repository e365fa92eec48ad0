// The simulator's AprilGrid is a real one: OpenCV's AprilTag detector finds every tag in a
// rendered frame, with the ids and corner positions that the landmarks say.
#include <gtest/gtest.h>

#include <opencv2/aruco.hpp>

#include <map>

#include "dsp/sim/rs_renderer.hpp"
#include "dsp/sim/calibration_target.hpp"

using namespace rsd;

TEST(AprilGrid, OpenCvDetectsEveryTagWhereTheLandmarksSay) {
  dsp::TargetSpec spec;
  spec.kind = dsp::TargetKind::AprilGrid;
  spec.rows = 4, spec.cols = 5, spec.spacing_m = 0.05;
  const dsp::Target target = dsp::make_target(spec);
  ASSERT_EQ(target.landmarks.size(), 4u * 4 * 5);

  dsp::CameraModel cam;
  cam.width = 800, cam.height = 600, cam.fx = cam.fy = 700, cam.cx = 399.5, cam.cy = 299.5;
  // A still camera 0.6 m in front of the grid, slightly turned so the tags are not axis-aligned.
  Eigen::Affine3d pose = Eigen::Affine3d::Identity();
  pose.linear() = dsp::exp_so3(Eigen::Vector3d(0.1, -0.15, 0.3));
  pose.translation() = Eigen::Vector3d(0.01, -0.02, 0.6);
  const dsp::FunctionMotion still([&](double) { return pose; });
  dsp::RenderOptions ro;
  ro.supersample = 4;
  dsp::RsRenderer r(cam, dsp::RowTiming::full_frame(600, 30), ro);
  dsp::Image img(cam.width, cam.height, dsp::PixelFormat::Mono8);
  r.render(target.scene, still, 0.0, img.view());

  const cv::Mat mat(img.height, img.width, CV_8UC1, img.data.data());
  const auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_APRILTAG_36h11);
  auto params = cv::aruco::DetectorParameters::create();
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<int> ids;
  cv::aruco::detectMarkers(mat, dict, corners, ids, params);
  ASSERT_EQ(ids.size(), 20u);

  std::map<int, Eigen::Vector3d> landmarks;
  for (const auto& L : target.landmarks) landmarks[L.id] = L.X;
  double worst = 0;
  for (size_t i = 0; i < ids.size(); ++i) {
    ASSERT_LT(ids[i], 20);
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d expected = cam.project(pose * landmarks.at(4 * ids[i] + k)).value();
      worst = std::max(worst, (expected - Eigen::Vector2d(corners[i][k].x, corners[i][k].y)).norm());
    }
  }
  EXPECT_LT(worst, 0.3);  // sub-pixel corner refinement on a rendered grid (measured 0.06)
}
