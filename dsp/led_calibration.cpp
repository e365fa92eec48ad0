#include "dsp/led_calibration.hpp"
