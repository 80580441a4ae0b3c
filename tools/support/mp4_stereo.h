// The Spherical Video V2 stereo box ('st3d') in the video sample entry of a
// finished MP4/MOV file, for ffmpeg-based players, YouTube and headset
// players that read the container's layout rather than the H.264
// frame-packing SEI. No GStreamer.
//
// Why after the fact: GStreamer 1.22's qtmux/mp4mux write no st3d box,
// and no muxer option adds one.
#pragma once

#include <cstdint>
#include <string>

namespace p3d {

// st3d's stereo_mode (Spherical Video V2 RFC): the left eye on top or on
// the left; the box has no value for the right eye first.
enum class Mp4StereoMode : uint8_t { Mono = 0, TopBottom = 1, LeftRight = 2 };

// Writes st3d with `mode` into the first video track's (handler 'vide')
// first sample entry, after its codec configuration box (avcC, hvcC), as
// the RFC places it: before the optional boxes (btrt, colr, pasp) at the
// entry's end. An st3d already there is replaced. The sizes of the boxes
// around it grow, and the chunk offsets (stco, co64) that point after the
// movie box move by the same amount. Fragmented files (moof, mfra) are
// refused: their fragments hold absolute offsets this does not move.
// When every mdat lies before moov (qtmux's default), only moov and what
// follows it are rewritten; otherwise the file is copied with the new
// moov and renamed over `path` (with its permissions). False with *error,
// the file unchanged, when it is not an MP4/MOV with a video track, is
// fragmented, or its top-level boxes do not run to its end (damaged or cut
// short); false as well when a write fails, which may leave the file
// damaged (the converter edits its temporary file, which it then deletes).
bool mp4_set_stereo_box(const std::string &path, Mp4StereoMode mode, std::string *error);

}  // namespace p3d
