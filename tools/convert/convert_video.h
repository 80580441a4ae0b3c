// A video file to a 3D video file:
//   filesrc ! decodebin ! (video chain, video_chain.h) ! encoder ! parser !
//   pseudo3dsignal ! mux ! filesink (temporary file beside OUTPUT)
// with the other streams copied or re-encoded (stream_copy.h), progress on
// stderr, and the file renamed to OUTPUT only when complete.
#pragma once

#include <string>

#include "options.h"

namespace p3d::convert {

// False with a one-line *error (naming the file concerned).
bool convert_video(const Options &o, std::string *error);

}  // namespace p3d::convert
