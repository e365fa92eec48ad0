#include "drivers/driver_registry.hpp"

#include "drivers/aravis_source.hpp"
#include "drivers/lcm_source.hpp"
#include "drivers/libcamera_source.hpp"
#include "drivers/recording_replay_source.hpp"
#include "drivers/replay_source.hpp"
#include "drivers/sim_source.hpp"
#include "drivers/v4l2_source.hpp"

namespace rsd::drivers {

const std::vector<Driver>& all_drivers() {
  static const std::vector<Driver> drivers = {sim_driver(),       aravis_driver(), v4l2_driver(),
                                              libcamera_driver(), replay_driver(), recording_driver(),
                                              lcm_driver()};
  return drivers;
}

const Driver* find_driver(const std::string& name) {
  for (const Driver& d : all_drivers())
    if (d.name == name) return &d;
  return nullptr;
}

std::string driver_names() {
  const auto& d = all_drivers();
  std::string s;
  for (size_t i = 0; i < d.size(); ++i) s += (i == 0 ? "" : i + 1 == d.size() ? " or " : ", ") + d[i].name;
  return s;
}

}  // namespace rsd::drivers
