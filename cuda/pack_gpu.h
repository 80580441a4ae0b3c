// GPU stereo packing: the function of common/pack.h.
#pragma once

#include "../common/pack.h"
#include "change_gpu.h"
#include "cuda_check.h"

namespace p3d {

// in, out: device memory; in packed RGB, out packed RGB of in's format or
// NV12/I420 (pack_args_valid()), sized by pack_size().
// Asynchronous on `stream`; no allocation, no state. Returns
// cudaErrorInvalidValue (launching nothing) when pack_args_valid() fails.
// Bit-identical to pack_cpu(): both call pack_pixel(). A closed gate
// (cuda/change_gpu.h: an adaptive stage keeping the frame) makes every
// kernel return at once.
CudaStatus pack_gpu(const PackParams &params, const FrameView &in, const FrameView &out, cudaStream_t stream,
                    StageGate gate = {});

}  // namespace p3d
