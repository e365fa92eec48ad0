#include <gtest/gtest.h>
#include "dsp/rs_optical_flow.hpp"
