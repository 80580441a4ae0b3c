// GPU cross-bilateral filter: the function of common/bilateral.h.
#pragma once

#include "../common/bilateral.h"
#include "cuda_check.h"
#include "device_buffer.h"

namespace p3d {

class BilateralFilterGpu {
 public:
  // guide, depth_in, depth_out: device memory; depth_in != depth_out.
  CudaStatus run(const BilateralParams &params, const FrameView &guide, ImageView<const float> depth_in,
                 ImageView<float> depth_out, cudaStream_t stream);

 private:
  DeviceBuffer tables_;  // space then range weights, uploaded when params change
  BilateralParams uploaded_{-1, 0.f, 0.f};
};

}  // namespace p3d
