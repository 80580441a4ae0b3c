// The point where a finished Matroska file gets its container stereo mode
// (tools/support/mkv_stereo.h, in place).
#pragma once

#include <string>

namespace p3d::convert {

// Called on the finished temporary .mkv (muxer closed, before the rename to
// OUTPUT) with the plugin's layout name and the eye order. The stream
// already carries the layout in its frame-packing SEI (x264) and
// pseudo3dsignal kept the muxer from writing its own, wrong StereoMode; this
// adds a correct StereoMode for players that read only the container.
//
// The layout maps onto Matroska's StereoMode: the side-by-side and
// top-bottom layouts (full or half: Matroska does not say) to theirs,
// interleaved and checkerboard to theirs, anaglyph and single views to mono.
// Returns false with *error when the file cannot be edited (it stays as it
// was, valid; the SEI still carries the layout).
bool set_mkv_container_stereo_mode(const std::string &path, const std::string &layout, bool right_first,
                                   std::string *error);

}  // namespace p3d::convert
