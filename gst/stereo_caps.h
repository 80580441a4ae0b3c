// GStreamer's multiview signalling for pseudo3dpack: which mode and flags a
// packed layout is signalled with, and which stereo arrangement an input's
// caps declare. Following GStreamer's conventions exactly:
//  * multiview-mode per layout (mono for anaglyph, left/right for one view);
//  * half-aspect on every layout whose views are squeezed (half side-by-side
//    and top-bottom, row/column interleaved, checkerboard), with the frame's
//    pixel-aspect-ratio left as it is (the flag says the views are squeezed;
//    counting it in the PAR as well would stretch them twice);
//  * right-view-first exactly when the right view comes first.
#pragma once

#include <gst/video/video.h>

#include "pack.h"

namespace p3d::gst {

struct MultiviewSignal {
  GstVideoMultiviewMode mode;
  GstVideoMultiviewFlags flags;
  int views;
};

// How the output of `layout` is signalled (swap_eyes: the right view comes
// first, or is the one view shown).
MultiviewSignal layout_signal(PackLayout layout, bool swap_eyes);
// How an input arrangement is signalled.
MultiviewSignal arrangement_signal(StereoInput arrangement, bool right_first);

// The stereo arrangement a caps' multiview mode and flags declare. False for
// mono or unsupported modes and flags, with *why saying what the input is.
bool arrangement_from_multiview(GstVideoMultiviewMode mode, GstVideoMultiviewFlags flags, StereoInput *arrangement,
                                bool *right_first, const char **why);
// The same read from a caps structure (fields absent: mono).
bool arrangement_from_structure(const GstStructure *s, StereoInput *arrangement, bool *right_first, const char **why);

// Writes multiview-mode, multiview-flags (with `mask`) and views into s.
void set_multiview_fields(GstStructure *s, const MultiviewSignal &sig, guint mask);

// The output caps of a stage that writes a packed stereo layout
// (pseudo3dpack, and pseudo3dwarp with a layout), from `s` (taken) with the
// output's size, multiview fields and packed formats: s itself first (kept
// unless downstream asks otherwise), then a 4:2:0 variant for encoders, in
// a colorimetry stated rather than left to GStreamer's size-based default
// (BT.2020 from 2160 rows up, which the R'G'B' views of BT.709 video are
// not): s's transfer and primaries with their matrix first
// (offer_yuv_colorimetry()); chroma-site jpeg: each chroma sample is the
// mean of its 2x2 block.
GstCaps *packed_output_caps(GstStructure *s);
// Whether a caps structure's format (a name or a list) names NV12 or I420.
bool names_yuv420(const GstStructure *s);

}  // namespace p3d::gst
