#include "tools/report/diagnosis_calibration.hpp"

#include <optional>

namespace rsd::tools {

namespace {

std::optional<double> sigma_of(const dsp::Diagnosis& d, const std::string& param) {
  for (const dsp::ParamUncertainty& u : d.uncertainties)
    if (u.param == param && u.sigma) return u.sigma;
  return std::nullopt;
}

// The sigma of a calibration key from the fit's parameters, if every element has one.
void add_sigma(formats::Calibration& c, const dsp::Diagnosis& d, const std::string& key, std::initializer_list<const char*> params) {
  std::vector<double> s;
  for (const char* p : params) {
    const auto v = sigma_of(d, p);
    if (!v) return;
    s.push_back(*v);
  }
  c.sigma[key] = s;
}

}  // namespace

formats::Calibration calibration_from(const dsp::Recording& rec, const dsp::Diagnosis& d, const std::string& source) {
  const dsp::NominalModel& nominal = rec.nominal;
  using dsp::Param;
  const dsp::ModelParams& p = d.fitted;  // full values: the nominal where no effect was named
  formats::Calibration c = formats::calibration_of(nominal, source);
  c.cam.fx = p[Param::Fx];
  c.cam.fy = p[Param::Fy];
  c.cam.dist = dsp::lens_of(nominal, p);  // the lens named: lens_distortion's terms, lens_model's family
  c.timeshift_cam_imu_s = p[Param::TimeOffset];  // t_imu = t_cam + offset, as time_offset_s
  c.line_delay_s = p[Param::LineDelay];
  c.readout = p.flip_readout ? (nominal.time.readout == dsp::Readout::TopToBottom ? dsp::Readout::BottomToTop
                                                                                 : dsp::Readout::TopToBottom)
                             : nominal.time.readout;
  c.drift_ppm = p[Param::Drift];
  c.gyro_bias_rad_s = {p[Param::BiasX], p[Param::BiasY], p[Param::BiasZ]};
  c.lever_arm_m = {p[Param::LeverX], p[Param::LeverY], p[Param::LeverZ]};
  c.cam.cx = p[Param::Cx];
  c.cam.cy = p[Param::Cy];
  c.gyro_scale = {p[Param::ScaleX], p[Param::ScaleY], p[Param::ScaleZ]};
  // mount_rotation: gyro recordings turn imu_to_camera into Exp(r) R_nominal. Trajectory
  // recordings turn the camera in the body (R_c = R Exp(r)): the body-to-camera rotation the
  // daemon applies to the body's rates is then Exp(r)^T (R_nominal is the identity there).
  const Eigen::Matrix3d E = dsp::mount_of(p);
  c.imu_to_camera = rec.motion == dsp::MotionKind::Trajectory ? Eigen::Matrix3d(E.transpose() * nominal.imu_to_camera)
                                                              : Eigen::Matrix3d(E * nominal.imu_to_camera);
  add_sigma(c, d, "line_delay_s", {"line_delay_s"});
  add_sigma(c, d, "timeshift_cam_imu", {"time_offset_s"});
  add_sigma(c, d, "drift_ppm", {"drift_ppm"});
  add_sigma(c, d, "gyro_bias_rad_s", {"bx", "by", "bz"});
  add_sigma(c, d, "lever_arm_m", {"x", "y", "z"});
  add_sigma(c, d, "gyro_scale", {"sx", "sy", "sz"});
  return c;
}

}  // namespace rsd::tools
