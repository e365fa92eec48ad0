#include "dsp/observation/recording.hpp"

namespace rsd::dsp {

const char* to_string(ObservationKind k) { return k == ObservationKind::Landmarks ? "landmarks" : "matches"; }
const char* to_string(MotionKind k) { return k == MotionKind::Trajectory ? "trajectory" : "gyro"; }

}  // namespace rsd::dsp
