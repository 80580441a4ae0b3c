// The device side of common/bars.h: the bar counts, and the warp inside
// an active rect (warp_pack_changed_cpu() with an ActiveArea, whole).
#pragma once

#include "../common/bars.h"
#include "cuda_check.h"
#include "device_buffer.h"
#include "warp_gpu.h"

namespace p3d {

// bar_counts_cpu() of frames in device memory: count() queues a frame's
// counts and their copy into pinned host memory on a stream of its own,
// behind the work queued so far on the caller's stream, so that the
// caller's next kernels do not wait behind the copy; join() makes the
// caller's stream wait for them (call it once the frame's other work is
// queued, before the frame may be released). take() waits for the copy
// (an event, not the whole stream) and hands the counts over, at the next
// frame where the tracker's order allows (common/bars.h, step 4). Call
// reset() with the context that count() used current before the object
// goes.
class BarCountsGpu {
 public:
  BarCountsGpu() = default;
  ~BarCountsGpu() { reset(); }
  BarCountsGpu(const BarCountsGpu &) = delete;
  BarCountsGpu &operator=(const BarCountsGpu &) = delete;

  CudaStatus count(const FrameView &frame, int luma_threshold, cudaStream_t stream);
  // After count(): `stream` waits for the count (no host wait).
  CudaStatus join(cudaStream_t stream);
  // After count(), where the caller queues nothing to join (an error
  // path): the host waits until the count has read the frame. The counts
  // stay for take().
  void settle();
  // False, with nothing written, when no count is queued.
  bool take(BarCounts *counts, CudaStatus *status);
  void reset();

 private:
  DeviceBuffer counts_;             // rows, then columns (uint32)
  uint32_t *host_ = nullptr;        // pinned, the same layout
  size_t host_values_ = 0;
  cudaStream_t side_ = nullptr;     // the counts' own stream
  cudaEvent_t ready_ = nullptr;     // the caller's stream up to count()
  cudaEvent_t done_ = nullptr;      // the counts copied
  bool pending_ = false, unjoined_ = false;
  int width_ = 0, height_ = 0;
};

// warp_pack_changed_cpu() with an ActiveArea (every row) on the device:
// the views of the picture inside `rect`, with active_warp_params(), into
// the pair's rows (a rect of the frame's width) or a pair of the rect's
// size placed into the pair; views_outside_gpu() around it; then
// pack_gpu() into dst unless dst is the pair. pair: dst where the layout
// is the pair itself, else device memory the caller keeps (packed RGB,
// 2W x H). The gate's rows (frame rows) are rendered into the kept pairs
// only; a dst that is the pair renders every row.
class ActiveWarpGpu {
 public:
  CudaStatus render(WarpRendererGpu &warp, const WarpParams &params, const PackParams &pack, const FrameView &src,
                    const YuvToRgb &m, DepthGrid<const float> depth, PixelRect rect, const FrameView &dst,
                    cudaStream_t stream, StageGate gate = {});

 private:
  DeviceBuffer pair_, active_pair_;
};

// views_outside_cpu() over every row, on the device.
CudaStatus views_outside_gpu(const FrameView &src, const YuvToRgb &m, PixelRect active, const FrameView &pair,
                             cudaStream_t stream, StageGate gate = {});

}  // namespace p3d
