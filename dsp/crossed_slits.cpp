#include "dsp/crossed_slits.hpp"
