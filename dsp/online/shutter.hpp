// What is known of a camera's rows (issue 36): whether they are read one after another (a rolling
// shutter, with a line delay between consecutive rows) or all at once (a global shutter), as
// configured and as the frames show it.
#pragma once

namespace rsd::dsp {

// Before any frame is seen. rolling: a line delay is given and refined; unknown: none is given
// (0: nobody measured it yet), so the frames are asked whether the rows are read at different
// times at all, the line delay fitted from 0 within the frame period; global: the camera has a
// global shutter (configured, or its driver knows), so there is no line delay to learn.
enum class Shutter { Rolling, Unknown, Global };

// What the frames have shown (the diagnosis's rolling_shutter question, asked online): undecided;
// rolling, a line delay beyond three sigmas of 0; global, the line delay known to its tolerance
// and within three sigmas of 0.
enum class RowsSeen { Undecided, Rolling, Global };

inline const char* to_string(Shutter s) {
  switch (s) {
    case Shutter::Rolling: return "rolling";
    case Shutter::Unknown: return "unknown";
    case Shutter::Global: return "global";
  }
  return "?";
}

inline const char* to_string(RowsSeen r) {
  switch (r) {
    case RowsSeen::Undecided: return "undecided";
    case RowsSeen::Rolling: return "rolling";
    case RowsSeen::Global: return "global";
  }
  return "?";
}

}  // namespace rsd::dsp
