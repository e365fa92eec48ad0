#include "dsp/two_view_bundle_adjustment.hpp"
