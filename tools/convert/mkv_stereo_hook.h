// The point where a finished Matroska file gets its container stereo mode.
#pragma once

#include <string>

namespace p3d::convert {

// Called on the finished temporary .mkv (muxer closed, before the rename to
// OUTPUT) with the plugin's layout name and the eye order. The stream
// already carries the layout in its frame-packing SEI (x264) and
// pseudo3dsignal kept the muxer from writing its own, wrong StereoMode; this
// adds a correct StereoMode for players that read only the container.
//
// The lead wires p3d::mkv_set_stereo_mode (tools/support/mkv_stereo.h) in
// here:
//   return p3d::mkv_set_stereo_mode(path, mkv_layout(layout), right_first, error);
// with layout -> p3d::MkvStereoLayout: side-by-side, side-by-side-half ->
// SideBySide; top-bottom, top-bottom-half -> TopBottom; row-interleaved ->
// RowInterleaved; column-interleaved -> ColumnInterleaved; checkerboard ->
// Checkerboard; anaglyph, left, right -> Mono.
// Until then it leaves the file as it is and succeeds.
bool set_mkv_container_stereo_mode(const std::string &path, const std::string &layout, bool right_first,
                                   std::string *error);

}  // namespace p3d::convert
