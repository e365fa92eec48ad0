#include "dsp/applicability.hpp"
