// The least structure the diagnosis calls physics: what no instrument here tells from its own
// bias. One limit for the three places that ask (an effect's size, selector.hpp; parallax's,
// parallax.hpp; the remainder's, remainder.hpp), so that what the selection refuses to name as
// too small is not then called significant physics in the remainder.
#pragma once

namespace rsd::dsp {

// Pixels, RMS per coordinate. OpenCV's checkerboard detector is biased by 0.005-0.03 px
// depending on the view (target_observations.cpp), and rsd-extract's tracker holds a field of its
// own of about 0.02 px against rsd-sim's rendering and 0.023 px against an independent renderer's
// (docs/diagnosis.md). On a board rendered by an independent generator, whose corners were found
// to 0.016 px with a bias of (0.010, 0.010) px, a lever arm of 16 um (BIC drop 2750) was named for
// that bias, moving the corners by 0.010 px.
inline constexpr double kInstrumentBiasPx = 0.03;

}  // namespace rsd::dsp
