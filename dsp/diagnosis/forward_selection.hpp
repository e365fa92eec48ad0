// The forward rounds of dsp::select_effects (select.cpp): each round screens every candidate
// effect on the subsample, refits the strongest on every fitting observation, compares
// hypotheses for the same structure head to head and names the winner if the checks let it
// (the held-out frames, plausibility, bounds, the bulk); two effects refused alone are asked
// together. Internal to the diagnosis; select.cpp checks the set they end with.
//
// Thread contract: as the Selector's (selector.hpp): one thread at a time per Selector.
#pragma once

#include <string>
#include <vector>

#include "dsp/diagnosis/selector.hpp"

namespace rsd::dsp::selection {

// Forward rounds from s (which ends as the state of the effects named) over `candidates` until
// no candidate clears the threshold; the steps in the order named. What the held-out frames
// refused and no later round named goes to `withheld` (each round asks every candidate again: a
// refused effect may be named once another is in).
std::vector<SelectedEffect> forward(const Selector& sel, const std::vector<Effect>& candidates, State& s,
                                    std::vector<std::string>& withheld);

}  // namespace rsd::dsp::selection
