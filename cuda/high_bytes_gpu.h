// The 8-bit copy of a deep frame that the GPU depth estimate and filter
// read (common/frame.h, high_byte): their kernels are 8-bit, and they use
// a deep frame's high 8 bits, as the CPU path does.
#pragma once

#include "../common/frame.h"
#include "cuda_check.h"
#include "device_buffer.h"

namespace p3d {

// high_byte_copy_cpu() of the first `planes` planes of deep frame `src`
// (device memory) into `out` (high_byte_format(src.format), src's size).
// No host sync.
CudaStatus high_byte_copy_gpu(const FrameView &src, const FrameView &out, cudaStream_t stream, int planes);

// A stage's 8-bit view of its input: the frame itself when it is 8-bit,
// else its high-byte copy in a buffer kept for the next frame.
class HighByteFrame {
 public:
  // *view8: the frame to read; the copy is launched on `stream`.
  // luma_only: a reader of load_luma() alone (the filter's guide), for
  // which a 4:2:0 copy gets its luma plane only, its chroma planes left
  // as the buffer holds them.
  CudaStatus of(const FrameView &src, cudaStream_t stream, FrameView *view8, bool luma_only = false);

 private:
  DeviceBuffer copy_;
};

}  // namespace p3d
