// GPU DIBR warp and hole filling: the function of common/warp.h.
#pragma once

#include "../common/warp.h"
#include "cuda_check.h"
#include "device_buffer.h"

namespace p3d {

class WarpRendererGpu {
 public:
  // src, depth, out: device memory (out is packed RGB, 2W x H). If
  // holes_out is not null, the hole count is copied back (a stream sync).
  // fill=NeighborAverage synchronises to test for remaining holes.
  CudaStatus render(const WarpParams &params, const FrameView &src, const YuvToRgb &m, ImageView<const float> depth,
                    const FrameView &out, cudaStream_t stream, long long *holes_out = nullptr);

 private:
  DeviceBuffer keys_, counters_, scratch_;
};

}  // namespace p3d
