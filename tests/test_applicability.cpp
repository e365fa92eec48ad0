#include <gtest/gtest.h>
#include "dsp/applicability.hpp"
