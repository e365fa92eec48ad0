// rsd's configuration: the defaults `rsd --print-default-config` prints are the structs'
// defaults (printed text read back gives the default Config, field by field); each driver
// reads its own section; bad values and unknown drivers are errors naming file, line and key.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "daemon/config.hpp"
#include "drivers/aravis_source.hpp"
#include "drivers/lcm_source.hpp"
#include "drivers/replay_source.hpp"
#include "drivers/sim_source.hpp"
#include "drivers/v4l2_source.hpp"
#include "tests/support/temp_dir.hpp"

namespace rsd {
namespace {

const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_config_");

std::string put(const std::string& name, const std::string& text) {
  const std::string path = g_tmp.path(name);
  std::ofstream(path) << text;
  return path;
}

daemon::Config load(const std::string& name, const std::string& text) { return daemon::load_config(put(name, text)); }

std::string error_of(const std::string& text) {
  try {
    load("bad.yaml", text);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

TEST(Config, PrintedDefaultsReadBackAsTheDefaults) {
  const daemon::Config d;
  const daemon::Config r = load("defaults.yaml", daemon::default_config_yaml());
  EXPECT_EQ(r.source.driver, d.source.driver);
  const auto& sim = r.source.settings_of<drivers::SimSourceConfig>("sim");
  const auto& sim0 = d.source.settings_of<drivers::SimSourceConfig>("sim");
  EXPECT_EQ(sim.camera.width, sim0.camera.width);
  EXPECT_EQ(sim.camera.height, sim0.camera.height);
  EXPECT_NEAR(sim.camera.fx, sim0.camera.fx, 1e-9 * sim0.camera.fx);
  EXPECT_EQ(sim.fps, sim0.fps);
  EXPECT_EQ(sim.exposure_s, sim0.exposure_s);
  EXPECT_EQ(sim.angular_rate, sim0.angular_rate);
  EXPECT_EQ(sim.velocity, sim0.velocity);
  EXPECT_EQ(sim.velocity_rate_hz, sim0.velocity_rate_hz);
  EXPECT_EQ(sim.realtime, sim0.realtime);
  const auto& ar = r.source.settings_of<drivers::AravisConfig>("aravis");
  EXPECT_EQ(ar.camera, drivers::AravisConfig{}.camera);
  EXPECT_EQ(ar.buffers, drivers::AravisConfig{}.buffers);
  EXPECT_EQ(ar.stamp, drivers::AravisConfig{}.stamp);
  EXPECT_EQ(r.source.settings_of<drivers::V4l2Config>("v4l2").device, drivers::V4l2Config{}.device);
  EXPECT_EQ(r.source.settings_of<drivers::ReplayConfig>("replay").speed, drivers::ReplayConfig{}.speed);
  EXPECT_EQ(r.source.settings_of<drivers::LcmSourceConfig>("lcm").url, drivers::LcmSourceConfig{}.url);
  EXPECT_EQ(r.pipeline.raw_slots, d.pipeline.raw_slots);
  EXPECT_EQ(r.pipeline.queue_depth, d.pipeline.queue_depth);
  EXPECT_EQ(r.rectify.reference, d.rectify.reference);
  EXPECT_EQ(r.rectify.depth, d.rectify.depth);
  EXPECT_EQ(r.rectify.grid_px, d.rectify.grid_px);
  EXPECT_EQ(r.velocity_limits.max_age_s, d.velocity_limits.max_age_s);
  EXPECT_EQ(r.velocity_input.imu_to_camera, d.velocity_input.imu_to_camera);
  EXPECT_EQ(r.lcm_url, d.lcm_url);
  EXPECT_EQ(r.channels.health, d.channels.health);
}

TEST(Config, EachDriverReadsItsOwnSection) {
  const daemon::Config c = load("drivers.yaml",
                                "source:\n"
                                "  driver: aravis\n"
                                "  camera: {width: 320, height: 240, fx: 300}\n"
                                "  aravis: {camera: Fake_1, buffers: 3, stamp: exposure_end}\n"
                                "  sim: {width: 160, height: 120, hfov_deg: 90}\n"
                                "  replay: {speed: fast}\n");
  EXPECT_EQ(c.source.driver, "aravis");
  const auto& a = c.source.settings_of<drivers::AravisConfig>("aravis");
  EXPECT_EQ(a.camera, "Fake_1");
  EXPECT_EQ(a.buffers, 3);
  EXPECT_EQ(a.stamp, drivers::CameraStamp::ExposureEnd);
  const auto& s = c.source.settings_of<drivers::SimSourceConfig>("sim");
  EXPECT_EQ(s.camera.width, 160);
  EXPECT_NEAR(s.camera.fx, 80.0 / std::tan(M_PI / 4), 1e-9);  // (w / 2) / tan(hfov / 2)
  EXPECT_EQ(c.source.settings_of<drivers::ReplayConfig>("replay").speed, 0.0);  // fast
  ASSERT_TRUE(c.source.camera.has_value());
  EXPECT_EQ(c.source.camera->width, 320);
}

// source.shutter: rolling by default; global reaches the simulator, which then reads every row
// at once (issue 36); anything else is refused naming the key.
TEST(Config, AGlobalShutterReachesTheSimulator) {
  EXPECT_EQ(load("rolling.yaml", "source:\n  driver: sim\n").source.shutter, dsp::Shutter::Rolling);
  const daemon::Config c = load("global.yaml", "source:\n  driver: sim\n  shutter: global\n");
  EXPECT_EQ(c.source.shutter, dsp::Shutter::Global);
  EXPECT_TRUE(c.source.settings_of<drivers::SimSourceConfig>("sim").global_shutter);
  drivers::SimSource sim(c.source.settings_of<drivers::SimSourceConfig>("sim"));
  sim.open();
  EXPECT_EQ(sim.timing().line_delay_s, 0.0);
  const std::string bad = error_of("source:\n  shutter: rolled\n");
  EXPECT_NE(bad.find("'source.shutter' must be"), std::string::npos) << bad;
}

// source.sim.lens: the simulated camera looks through a fisheye whose hfov_deg spans the width:
// a ray hfov / 2 off the axis, horizontal, projects onto the image's edge (half a pixel past
// the last pixel centre), through the lens's own projection.
TEST(Config, TheSimulatedCameraLooksThroughTheLensItIsGiven) {
  const daemon::Config c = load("fisheye.yaml",
                                "source:\n  sim:\n    hfov_deg: 120\n"
                                "    lens: {model: pinhole-equi, k1: 0.02, k2: -0.004, k3: 0.001, k4: 0}\n");
  const dsp::CameraModel& cam = c.source.settings_of<drivers::SimSourceConfig>("sim").camera;
  EXPECT_EQ(cam.dist, dsp::Distortion::equidistant(0.02, -0.004, 0.001, 0));
  const double half = 60 * M_PI / 180;
  const auto edge = cam.project({std::sin(half), 0, std::cos(half)});
  ASSERT_TRUE(edge.has_value());
  EXPECT_NEAR(edge->x(), 639.5, 1e-9);
  EXPECT_NEAR(edge->y(), 239.5, 1e-9);
  // Without a lens, the pinhole as before.
  const daemon::Config p = load("pinhole.yaml", "source:\n  sim: {hfov_deg: 90}\n");
  EXPECT_NEAR(p.source.settings_of<drivers::SimSourceConfig>("sim").camera.fx, 320.0, 1e-12);
}

TEST(Config, ASimulatedLensThatCannotBeRenderedIsRefusedNamingIt) {
  EXPECT_NE(error_of("source:\n  sim:\n    lens: {model: pinhole-equi, p1: 0.1}\n")
                .find("'source.sim.lens.p1' and p2 are pinhole-radtan's: pinhole-equi has no tangential terms"),
            std::string::npos);
  EXPECT_NE(error_of("source:\n  sim:\n    lens: {model: pinhole-radtan, k4: 0.1}\n").find("'source.sim.lens.k4' is pinhole-equi's"),
            std::string::npos);
  EXPECT_NE(error_of("source:\n  sim:\n    lens: {model: fisheye}\n").find("'source.sim.lens.model' must be pinhole-radtan or pinhole-equi"),
            std::string::npos)
      << error_of("source:\n  sim:\n    lens: {model: fisheye}\n");
  // 160 degrees across 640 px puts the corners 100 degrees off the axis: beyond the model.
  const std::string wide = error_of("source:\n  sim:\n    hfov_deg: 160\n    lens: {model: pinhole-equi}\n");
  EXPECT_NE(wide.find("bad.yaml:4:11: 'source.sim.lens' has no ray through pixel (0, 0)"), std::string::npos) << wide;
}

// source.calibration_file: the camera's intrinsics, the drivers' row timing (replacing their
// own), the velocity input's IMU corrections; intrinsics given twice are refused.
TEST(Config, ACalibrationFileReachesCameraDriversAndVelocityInput) {
  put("cal.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, 301, 159.5, 119.5]
  distortion_model: radtan
  distortion_coeffs: [0.01, 0, 0, 0]
  resolution: [320, 240]
  T_cam_imu:
  - [0, -1, 0, 0]
  - [1, 0, 0, 0]
  - [0, 0, 1, 0]
  - [0, 0, 0, 1]
  timeshift_cam_imu: 0.0123
  rsd:
    format: rsd-calibration/1
    line_delay_s: 5.0e-05
    readout: bottom_to_top
    gyro_bias_rad_s: [0.001, 0.002, 0.003]
    gyro_scale: [1.01, 1, 1]
)");
  const daemon::Config c = load("with-cal.yaml", "source:\n  driver: aravis\n  calibration_file: cal.yaml\n"
                                                 "  aravis: {camera: Fake_1, line_delay_s: 1.0e-05}\n");
  ASSERT_TRUE(c.source.camera.has_value());
  EXPECT_EQ(c.source.camera->fy, 301);
  EXPECT_EQ(c.source.camera->dist.k1, 0.01);
  const auto& a = c.source.settings_of<drivers::AravisConfig>("aravis");
  EXPECT_EQ(a.line_delay_s, 5e-5);  // the calibration's, over the section's own
  EXPECT_EQ(a.readout, dsp::Readout::BottomToTop);
  EXPECT_EQ(c.velocity_input.imu_time_offset_s, 0.0123);
  EXPECT_EQ(c.velocity_input.gyro_bias_rad_s, Eigen::Vector3d(0.001, 0.002, 0.003));
  EXPECT_EQ(c.velocity_input.gyro_scale, Eigen::Vector3d(1.01, 1, 1));
  EXPECT_EQ(c.velocity_input.imu_to_camera * Eigen::Vector3d::UnitX(), Eigen::Vector3d(0, 1, 0));
  // The camera delivering another size is refused, naming the calibration.
  try {
    daemon::camera_model(c.source, {640, 480, dsp::PixelFormat::Mono8});
    FAIL() << "a calibration for another resolution must be refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cal.yaml (cam0) says 320x240, but the camera delivers 640x480"), std::string::npos)
        << e.what();
  }
  EXPECT_NE(error_of("source:\n  driver: aravis\n  camera: {width: 320, height: 240, fx: 300}\n  calibration_file: cal.yaml\n")
                .find("cal.yaml: the calibration's intrinsics and source.camera both give the camera: keep one"),
            std::string::npos);
  EXPECT_NE(error_of("source:\n  sim: {width: 320, height: 240}\n  calibration_file: cal.yaml\nvelocity:\n  imu_to_camera: [1, 0, 0, 0, 0, -1, 0, 1, 0]\n")
                .find("cal.yaml: the calibration's T_cam_imu and velocity.imu_to_camera both rotate the IMU: keep one"),
            std::string::npos);
  // Issue 36: a global shutter has no line delay; a calibration that gives one is refused,
  // naming both.
  const std::string global = error_of("source:\n  driver: aravis\n  shutter: global\n  calibration_file: cal.yaml\n"
                                      "  aravis: {camera: Fake_1}\n");
  EXPECT_NE(global.find("cal.yaml: cam0.rsd.line_delay_s is 5e-05 s, but source.shutter is global"), std::string::npos) << global;
  // Issue 38: a calibration for another size than the simulator renders is refused by the
  // check, not when the first frame comes (at start, or over SIGHUP).
  EXPECT_NE(error_of("source:\n  calibration_file: cal.yaml\n").find("gives intrinsics for 320x240, but source.sim asks the camera for 640x480"),
            std::string::npos)
      << error_of("source:\n  calibration_file: cal.yaml\n");
}

TEST(Config, BadValuesNameFileLineAndKey) {
  EXPECT_NE(error_of("source:\n  driver: webcam\n").find("bad.yaml:2:11: 'source.driver' must be sim, aravis, v4l2, libcamera, replay, recording or lcm"),
            std::string::npos)
      << error_of("source:\n  driver: webcam\n");
  EXPECT_NE(error_of("source:\n  sim: {readout: sideways}\n").find("'source.sim.readout' must be top_to_bottom or bottom_to_top"),
            std::string::npos);
  EXPECT_NE(error_of("source:\n  aravis: {buffers: many}\n").find("'source.aravis.buffers' must be an integer"), std::string::npos);
  EXPECT_NE(error_of("source:\n  driver: v4l2\n").find("'source.driver' 'v4l2' needs the camera's intrinsics"), std::string::npos)
      << error_of("source:\n  driver: v4l2\n");
  EXPECT_NE(error_of("pipeline: {queue_depth: 0}\n").find("'pipeline.queue_depth' must be 1..64"), std::string::npos);
  EXPECT_NE(error_of("rectification: {depth: sky}\n").find("'rectification.depth' must be infinite, plane or ground"),
            std::string::npos);
  EXPECT_NE(error_of("rectification: {imu_wait_ms: -1}\n").find("bad.yaml:1:30: 'rectification.imu_wait_ms' must be 0..1000 ms"),
            std::string::npos)
      << error_of("rectification: {imu_wait_ms: -1}\n");
  // A multicast URL is refused when read, never opened (spelled in two parts: no multicast
  // URL stands in the tests, so none can be used by mistake).
  const std::string multicast = std::string("udp") + "m://239.255.76.67:7667";
  EXPECT_NE(error_of("lcm: {url: \"" + multicast + "\"}\n").find("'lcm.url' is multicast"), std::string::npos);
  // Issue 16, defect 6: a width of -2^31 overflowed the default principal point.
  EXPECT_NE(error_of("source:\n  camera: {width: -2147483648, height: 480, fx: 500}\n").find("'source.camera.width' must be 4..8000 pixels"),
            std::string::npos)
      << error_of("source:\n  camera: {width: -2147483648, height: 480, fx: 500}\n");
  EXPECT_NE(error_of("velocity: {imu_to_camera: [1, 0, 0, 0, 1, 0, 0, 0, 2]}\n").find("must be a rotation matrix"), std::string::npos);
}

// Issue 16, defect 2: a complex key (YAML's "? [a, b]") made yaml-cpp throw its own exception
// past the configuration's error handling; it is a ConfigError naming file, line and section.
TEST(Config, AComplexKeyIsAConfigErrorNotAYamlException) {
  const std::string top = error_of("? [a, b]\n: 1\n");
  EXPECT_NE(top.find("bad.yaml:1:3: 'document' has a key that is not a plain name"), std::string::npos) << top;
  const std::string nested = error_of("pipeline:\n  ? {x: 1}\n  : 2\n");
  EXPECT_NE(nested.find("bad.yaml:2:5: 'pipeline' has a key that is not a plain name"), std::string::npos) << nested;
  try {
    load("bad.yaml", "source:\n  ? [sim]\n  : 1\n");
    ADD_FAILURE() << "no error";
  } catch (const formats::ConfigError&) {
  }
}

}  // namespace
}  // namespace rsd
