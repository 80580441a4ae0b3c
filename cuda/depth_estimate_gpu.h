// GPU depth estimation: the function of common/depth_estimate.h. Stateful
// like DepthEstimatorCpu (temporal history stays on the device; the
// reuse/smooth/cut decision is taken on the device, so no host sync).
//
// One estimate() queues, on the given stream and without host sync:
//   memset    the fixed-point |difference| sum in the device state, only
//             where the last frame's depth kernel did not clear it (it
//             clears the next frame's, which takes the other of two states)
//   features  block sums in integers -> means (step 1), and each block's
//             |feature - reference| added to the device sum (step 5); a
//             4:2:0 frame with 4-byte aligned rows is read four columns a
//             32-bit load
//   labels    the smoothed features of step 2 (the decision of step 5 is
//             derived from the device sum first: a cut restarts them), then
//             union-find in shared memory per 32x32 tile of blocks, then
//             across tile borders (atomicCAS hooking: a root only ever points
//             to a smaller index, so roots are the smallest index, step 2)
//   resolve   every block's root, and the region sums of hq (64-bit), block
//             counts and maxima of hq (ground contact) with integer atomics
//             (steps 3-4, exact)
//   depth     step 4 and the temporal step: every thread derives the decision
//             from the device sum (same input, same function, same answer),
//             thread 0 records it in the device state; the reference features
//             are updated unless the frame is reused
//   expand    block depth -> full-resolution float depth (step 6); into a
//             grid at the blocks' own cells the depth kernel writes each
//             block's value instead, and nothing is expanded
// Buffers are DeviceBuffer members grown when the block grid grows.
#pragma once

#include <vector>

#include "../common/depth_estimate.h"
#include "change_gpu.h"
#include "cuda_check.h"
#include "device_buffer.h"
#include "high_bytes_gpu.h"

namespace p3d {

class DepthEstimatorGpu {
 public:
  // frame and depth are device memory; work is queued on `stream`.
  CudaStatus estimate(const DepthParams &params, const FrameView &frame, ImageView<float> depth, cudaStream_t stream);
  // The same into a grid: shift 0 is the full-size map above; a shift > 0
  // must be log2 of effective_block_size() (block_grid_shift()), and the
  // grid then gets one value a block, written by the depth kernel, with no
  // expansion (cudaErrorInvalidValue, nothing queued, for another shift or
  // a grid not of the frame's size).
  // changes (adaptive, as DepthEstimatorCpu::estimate_blocks): the tiles of
  // `frame` that differ from the previous call's frame, on the device. The
  // features kernel's CTAs whose pixels lie in no such tile keep the
  // previous features (the same pixels give the same sums), and a reused
  // frame leaves steps 2-4 out (labels then describe the last frame that
  // used them). The output is that of a call without `changes`.
  CudaStatus estimate(const DepthParams &params, const FrameView &frame, DepthGrid<float> depth, cudaStream_t stream,
                      const TileFlags *changes = nullptr);
  void reset();

  // For tests (synchronise the stream, copy to host).
  CudaStatus download_labels(std::vector<int> &labels, cudaStream_t stream) const;
  CudaStatus download_block_depth(std::vector<float> &block_depth, cudaStream_t stream) const;
  // Step 2's smoothed features, 3 per block (as DepthEstimatorCpu::smoothed_features()).
  CudaStatus download_smoothed_features(std::vector<float> &smoothed, cudaStream_t stream) const;
  CudaStatus last_decision(TemporalDecision *decision, cudaStream_t stream) const;
  // Mean |feature difference| of the last frame (as DepthEstimatorCpu::last_diff()).
  CudaStatus last_diff(float *diff, cudaStream_t stream) const;

  int blocks_x() const { return bx_; }
  int blocks_y() const { return by_; }

 private:
  // features_/ref_features_/smoothed_features_: 3 floats a block; labels_: int a block (the
  // union-find forest, then the labels); region_sums_: uint64 a block;
  // region_counts_, region_max_: uint32 a block; block_depth_: float a block, the output
  // of the last frame; state_: two DepthDeviceStates (depth_estimate.cu).
  HighByteFrame high_bytes_;  // a deep input's 8-bit copy (cuda/high_bytes_gpu.h)
  DeviceBuffer features_, ref_features_, smoothed_features_, labels_, region_sums_, region_counts_, region_max_, block_depth_, state_;
  int bx_ = 0, by_ = 0, block_ = 0, width_ = 0, height_ = 0;
  bool have_state_ = false;
  // state_ holds two DepthDeviceStates, the last frame's at state_slot_;
  // next_state_zeroed_: the last frame's depth kernel cleared the other.
  int state_slot_ = 0;
  bool next_state_zeroed_ = false;
};

// depth(x, y) = depth_from_grey(grey, x, y, m) for every pixel (device memory).
CudaStatus depth_from_grey_gpu(const FrameView &grey, const YuvToRgb &m, ImageView<float> depth, cudaStream_t stream);

}  // namespace p3d
