// pseudo3d-convert --benchmark INPUT: what the converter adds to decoding.
// In one process, alternately (--benchmark-runs times each):
//  * decode-only: the converter's own input side (filesrc ! decodebin with
//    the same decoder choice, NVDEC and CUDA memory on the GPU path) into
//    queue ! fakesink;
//  * convert-fakesink: the same input side and the whole video chain of a
//    conversion (pseudo3dconvert with the chosen layout, the download and
//    the conversion to the encoder's raw format) with the encoder replaced
//    by fakesink.
// Other streams stay encoded and go to fakesinks in both. Frames per second
// run from the first frame to EOS (start-up excluded; wall time including
// it is reported too). Prints a table and appends JSON lines to
// --benchmark-out.
#pragma once

#include <string>

#include "options.h"

namespace p3d::convert {

bool run_benchmark(const Options &o, std::string *error);

}  // namespace p3d::convert
