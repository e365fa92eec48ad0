#include "dsp/paper_experiment.hpp"
