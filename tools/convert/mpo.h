// A stereo pair as an MPO file (CIPA DC-007 Multi-Picture Format), as 3D
// cameras write it (Fujifilm FinePix REAL 3D, Nintendo 3DS) and 3D TVs and
// viewers read it: two JPEG files back to back, the left view first. The
// first carries an APP2 "MPF" segment with the MP Index IFD (two MP entries
// giving each image's type, size and offset) and its MP Attribute IFD; the
// second an APP2 "MPF" with its own MP Attribute IFD. Both entries have the
// type "multi-frame disparity image" (0x020002), the first also the
// representative-image flag, so that 2D viewers show it.
#pragma once

#include "jpeg_meta.h"

namespace p3d::convert {

// `left` and `right`: complete JPEG files of the two views; `exif`: the
// EXIF block both get (an MPO's images are Exif JPEGs).
Bytes make_mpo(const Bytes &left, const Bytes &right, const Bytes &exif);

// MP type codes (CIPA DC-007 5.2.3.3.1) and the representative flag.
constexpr uint32_t kMpTypeDisparity = 0x020002;
constexpr uint32_t kMpFlagRepresentative = 0x20000000;

}  // namespace p3d::convert
