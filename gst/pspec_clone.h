// A property of one element offered by another under the same name, range,
// default and blurb: pseudo3dconvert offers its stages' properties (the
// pack's through stereo_packing.h, which makes their specs).
#pragma once

#include <gst/gst.h>

namespace p3d::gst {

// A new pspec like `p` (enum, int, float or boolean), readable and
// writable, keeping p's mutability flags (GST_PARAM_MUTABLE_*).
GParamSpec *clone_pspec(GParamSpec *p);

}  // namespace p3d::gst
