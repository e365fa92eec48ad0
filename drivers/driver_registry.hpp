// Every camera driver rsd has, in the order the default configuration shows them.
#pragma once

#include <string>
#include <vector>

#include "drivers/driver.hpp"

namespace rsd::drivers {

const std::vector<Driver>& all_drivers();
// nullptr for a name no driver has.
const Driver* find_driver(const std::string& name);
// "sim, aravis, v4l2, libcamera, replay or lcm", for messages.
std::string driver_names();

}  // namespace rsd::drivers
