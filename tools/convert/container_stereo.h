// The point where a finished file gets the stereo signalling of its
// container (tools/support/mkv_stereo.h, mp4_stereo.h), in place, on the
// temporary file before the rename to OUTPUT. The stream already carries
// the layout in its frame-packing SEI (x264), and pseudo3dsignal kept the
// muxer from writing its own, wrong signalling; these add what players
// that read only the container need.
#pragma once

#include <string>

namespace p3d::convert {

// Matroska: the layout maps onto StereoMode: the side-by-side and
// top-bottom layouts (full or half: Matroska does not say) to theirs,
// interleaved and checkerboard to theirs, anaglyph and single views to mono.
// Returns false with *error when the file cannot be edited (it stays as it
// was, valid; the SEI still carries the layout).
bool set_mkv_container_stereo_mode(const std::string &path, const std::string &layout, bool right_first,
                                   std::string *error);

// MP4/MOV: the Spherical Video V2 st3d box, left-right for the side-by-side
// layouts and top-bottom for the top-bottom ones (full or half: st3d does
// not say). The box has no value for the right eye first and none for the
// other layouts: those files get no box, and the SEI alone carries them.
// False with *error when the file cannot be edited.
bool set_mp4_stereo_box(const std::string &path, const std::string &layout, bool right_first, std::string *error);
// Whether set_mp4_stereo_box() writes a box for this layout and eye order.
bool mp4_stereo_box_says(const std::string &layout, bool right_first);

}  // namespace p3d::convert
