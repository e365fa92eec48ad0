#include <gtest/gtest.h>
#include "dsp/crossed_slits.hpp"
