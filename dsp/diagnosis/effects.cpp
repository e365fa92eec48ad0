#include "dsp/diagnosis/effects.hpp"

namespace rsd::dsp {

const char* effect_name(Effect e) {
  static constexpr const char* kNames[] = {"rolling_shutter", "time_offset",    "readout_direction", "clock_drift",
                                           "lens_distortion", "focal_length", "gyro_bias",         "lever_arm",
                                           "mount_rotation",  "gyro_scale",   "principal_point",   "lens_model"};
  static_assert(sizeof kNames / sizeof kNames[0] == static_cast<int>(Effect::Count));
  return kNames[static_cast<int>(e)];
}

ParamMask effect_params(Effect e, LensModel nominal_lens) {
  ParamMask m;
  auto set = [&](Param p) { m.set(static_cast<int>(p)); };
  auto radial = [&](LensModel family) {
    set(Param::K1), set(Param::K2);
    if (family == LensModel::PinholeEqui) set(Param::K3), set(Param::K4);
  };
  const LensModel other = nominal_lens == LensModel::PinholeEqui ? LensModel::PinholeRadtan : LensModel::PinholeEqui;
  switch (e) {
    case Effect::RollingShutter: set(Param::LineDelay); break;
    case Effect::TimeOffset: set(Param::TimeOffset); break;
    case Effect::ReadoutDirection: break;  // discrete: the flip
    case Effect::ClockDrift: set(Param::Drift); break;
    case Effect::LensDistortion: radial(nominal_lens); break;
    case Effect::LensModel: radial(other); break;
    case Effect::FocalLength: set(Param::Fx); break;  // fy follows at the nominal aspect (set_param)
    case Effect::GyroBias: set(Param::BiasX), set(Param::BiasY), set(Param::BiasZ); break;
    case Effect::LeverArm: set(Param::LeverX), set(Param::LeverY), set(Param::LeverZ); break;
    case Effect::MountRotation: set(Param::MountX), set(Param::MountY), set(Param::MountZ); break;
    case Effect::GyroScale: set(Param::ScaleX), set(Param::ScaleY), set(Param::ScaleZ); break;
    case Effect::PrincipalPoint: set(Param::Cx), set(Param::Cy); break;
    case Effect::Count: break;
  }
  return m;
}

std::vector<Effect> applicable_effects(const DiagnosisModel& m) {
  std::vector<Effect> out;
  for (int k = 0; k < static_cast<int>(Effect::Count); ++k) {
    const Effect e = Effect(k);
    if (e == Effect::GyroBias && !m.has_gyro()) continue;
    if (e == Effect::LeverArm && m.has_gyro()) continue;
    if (e == Effect::GyroScale && !m.has_gyro()) continue;
    out.push_back(e);
  }
  return out;
}

ParamMask mask_of(const std::vector<Effect>& effects, LensModel nominal_lens) {
  ParamMask mask;
  for (Effect e : effects) mask |= effect_params(e, nominal_lens);
  return mask;
}

}  // namespace rsd::dsp
