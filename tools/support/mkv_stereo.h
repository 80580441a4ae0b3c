// Stereo-3D signalling in the container of a finished Matroska/WebM file,
// for players that read only the container (not the H.264/H.265
// frame-packing SEI that pseudo3dsignal writes). No GStreamer.
//
// Why after the fact: GStreamer 1.22's matroskamux writes StereoMode 9
// (column interleaved in the Matroska spec) for right-first side by side,
// nothing for row/column interleaved, and a DisplayWidth/DisplayHeight
// that GStreamer reads as the whole frame but ffmpeg as one view. So the
// pipeline strips the multiview caps before the muxer (pseudo3dsignal) and
// this patches the finished file.
#pragma once

#include <string>

#include "pack.h"

namespace p3d {

// Half vs full views is not a Matroska property (no field carries it;
// readers guess it from the display aspect ratio), hence no "half" layouts.
enum class MkvStereoLayout { Mono, SideBySide, TopBottom, RowInterleaved, ColumnInterleaved, Checkerboard };

// The Matroska arrangement of a packed layout: side by side and top-bottom
// (full or half) to theirs, interleaved and checkerboard to theirs, the
// anaglyph and single views to mono.
MkvStereoLayout mkv_stereo_layout_of(PackLayout layout);
// A layout named as the plugin names it (kPackLayoutNames), or "mono";
// false for any other name.
bool mkv_stereo_layout_from_name(const std::string &name, MkvStereoLayout *layout);

// The Matroska StereoMode value (RFC 9559 / ebml_matroska.xml): 0 mono,
// 1/11 side by side left/right eye first, 3/2 top-bottom left/right eye
// first (first = on top), 5/4 checkerboard, 7/6 row interleaved, 9/8 column
// interleaved (odd = left eye first). right_first is ignored for Mono.
int mkv_stereo_mode_value(MkvStereoLayout layout, bool right_first);

// False only for column interleaved left eye first (9): GStreamer's
// matroskademux (1.22 and still on main) reads 9 as side by side right eye
// first, and h264parse then prefers that to the SEI, so 9 would break
// GStreamer playback. Without a StereoMode every reader takes the layout
// from the SEI; only container-only players miss it for that one layout.
bool mkv_stereo_mode_written(MkvStereoLayout layout, bool right_first);

// Writes the stereo signalling into the first video track (TrackType 1) of
// a finished Matroska/WebM file, in place:
//   StereoMode = mkv_stereo_mode_value(layout, right_first) (any existing
//     one removed; none written where mkv_stereo_mode_written is false),
//   DisplayWidth = PixelWidth, DisplayHeight = PixelHeight: GStreamer's
//     matroskademux takes the pixel aspect ratio as DisplayWidth*PixelHeight
//     / (DisplayHeight*PixelWidth) and guesses half/full views from it, and
//     with no display size it guesses wrong (never half for side by side,
//     always half for top-bottom). A file's non-square container PAR is
//     replaced by 1/1 (the project's pipelines always send square pixels).
//   DisplayUnit = 4 ("unknown"): ffmpeg then ignores the display size (it
//     would take it as one view's size and report SAR 2:1 for side by side)
//     and uses the codec's SAR.
// Nothing outside the Tracks element moves: the Tracks element is rebuilt
// to its old length (the size fields of its inner masters re-encoded to
// their shortest length, any Void inside dropped, the rest filled with one
// Void), so SeekHead, Cues and Cluster offsets stay valid. matroskamux
// writes those masters with 8-byte size fields, which leaves room; where
// that is not enough (mkvmerge's files), a Void right behind Tracks is
// taken in, as nothing points into a Void. CRC-32 elements in rebuilt
// masters are recomputed. For DocType "matroska" a
// DocTypeVersion below 3 is raised to 3 in place (StereoMode is a version 3
// element).
// WebM allows StereoMode only for mono, side by side and top-bottom; other
// layouts are refused there.
// Meant for files whose H.264/H.265 frame-packing SEI already carries the
// eye order (pseudo3dsignal before the muxer): GStreamer ignores StereoMode
// 6, 7, 8 and 11 and takes the layout from the SEI, and x264 alone always
// writes "left first" there.
// Returns false with *error (the file unchanged and valid) when the file
// is not Matroska/WebM, is truncated or corrupt, has no video track, or the
// Tracks element has no room for the new fields.
bool mkv_set_stereo_mode(const std::string &path, MkvStereoLayout layout, bool right_first, std::string *error);

}  // namespace p3d
