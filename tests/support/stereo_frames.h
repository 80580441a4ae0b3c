// Stereo frames for the pack tests, built from the definitions in
// common/pack.h's header comment with code of their own (never through
// pack_pixel), so the tests compare pack_cpu, pack_gpu and the element
// against an independent reference.
#pragma once

#include "host_frame.h"
#include "pack.h"

namespace p3d::test {

// A frame holding the views l and r (RGBA, same size) as `input` says.
HostFrame arrange_pair(StereoInput input, bool right_first, const HostFrame &l, const HostFrame &r);

// View `eye` (0 left, 1 right) of a frame holding a pair as `input` says, at
// its full display size: the reconstruction pack_pixel documents (samples of
// half formats interpolated, interleaved and checkerboard gaps averaged).
HostFrame reference_view(StereoInput input, bool right_first, const HostFrame &frame, int eye);

}  // namespace p3d::test
