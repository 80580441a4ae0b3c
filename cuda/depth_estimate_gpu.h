// GPU depth estimation: the function of common/depth_estimate.h. Stateful
// like DepthEstimatorCpu (temporal history stays on the device; the
// reuse/smooth/cut decision is taken on the device, so no host sync).
#pragma once

#include <vector>

#include "../common/depth_estimate.h"
#include "cuda_check.h"
#include "device_buffer.h"

namespace p3d {

class DepthEstimatorGpu {
 public:
  // frame and depth are device memory; work is queued on `stream`.
  CudaStatus estimate(const DepthParams &params, const FrameView &frame, ImageView<float> depth, cudaStream_t stream);
  void reset();

  // For tests (synchronise the stream, copy to host).
  CudaStatus download_labels(std::vector<int> &labels, cudaStream_t stream) const;
  CudaStatus download_block_depth(std::vector<float> &block_depth, cudaStream_t stream) const;
  CudaStatus last_decision(TemporalDecision *decision, cudaStream_t stream) const;

 private:
  DeviceBuffer sums_, features_, ref_features_, labels_, region_sums_, block_depth_, prev_block_depth_, state_;
  int bx_ = 0, by_ = 0, block_ = 0, width_ = 0, height_ = 0;
  bool have_state_ = false;
};

// depth(x, y) = depth_from_grey(grey, x, y, m) for every pixel (device memory).
CudaStatus depth_from_grey_gpu(const FrameView &grey, const YuvToRgb &m, ImageView<float> depth, cudaStream_t stream);

}  // namespace p3d
