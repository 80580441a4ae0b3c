// A photo to a 3D picture:
//  1. decoded and turned upright by its EXIF orientation (the depth
//     hypotheses are about the upright scene: "near at the bottom");
//  2. appsrc ! pseudo3ddepth ! pseudo3dfilter ! pseudo3dwarp ! pseudo3dpack
//     ! appsink, on the CPU, or on the GPU between one cudaupload and one
//     cudadownload; for --depth-out a tee after pseudo3dfilter takes the
//     depth pseudo3dwarp renders from through pseudo3ddepthout, encoded as a
//     16-bit PNG;
//  3. written as the packed picture (.jpg with the photo's EXIF, .png), an
//     MPO of the two views (mpo.h) or a JPS (the cross-eyed pair: right view
//     on the left, full width).
#pragma once

#include <string>

#include "options.h"

namespace p3d::convert {

bool convert_photo(const Options &o, std::string *error);

}  // namespace p3d::convert
