#include "dsp/rs_optical_flow.hpp"
