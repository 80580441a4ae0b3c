// Colour signalling through the stages that turn Y'CbCr into R'G'B' views
// and back (pseudo3dwarp, pseudo3dpack).
//
// The stages convert with the caps' matrix (video_util.h) and never touch
// the transfer function or the primaries: the code values leave in the
// transfer and primaries they came in with (PQ, HLG, BT.2020 or BT.709),
// so the output caps must say those, whatever the matrix. HDR metadata
// (mastering-display-info, content-light-level) rides in the caps
// structure, which the stages copy, so it passes untouched.
#pragma once

#include <gst/video/video.h>

namespace p3d::gst {

// The colorimetry a caps structure states in one "colorimetry" string,
// with a known transfer and primaries; false when it states none, a list,
// or leaves either unknown (jpegdec's 1:4:0:0): nothing to carry then,
// and the output is labelled as a stage without this labels it (sRGB for
// R'G'B', BT.709 first for 4:2:0).
bool stated_colorimetry(const GstStructure *s, GstVideoColorimetry *c);

// Sets the "colorimetry" of `rgb` (R'G'B' views made from input `in`) to
// full range, the RGB matrix, and in's transfer and primaries. Leaves rgb
// without one when `in` states none.
void carry_colour_to_rgb(const GstStructure *in, GstStructure *rgb);

// Sets the "colorimetry" of `yuv` (the 4:2:0 output made from R'G'B'
// caps `rgb`): a list of the Y'CbCr colorimetries with rgb's transfer and
// primaries in limited range, the matrix that belongs to the primaries
// first (BT.2020 primaries: BT.2020; SMPTE 170M and BT.470 BG: BT.601;
// any other: BT.709). Without a stated colorimetry in rgb: BT.709, BT.601,
// BT.2020 as they are named in GStreamer.
void offer_yuv_colorimetry(const GstStructure *rgb, GstStructure *yuv);

// Whether the transfer carries HDR code values (PQ or HLG), which an
// anaglyph's colour mixing must not be fed.
bool is_hdr_transfer(GstVideoTransferFunction transfer);

}  // namespace p3d::gst
