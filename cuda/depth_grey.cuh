// depth_from_grey_gpu's kernel (cuda/depth_estimate_gpu.h), built in each
// translation unit that includes this file: cuda/depth_estimate.cu for
// 8-bit grey pictures, cuda/kernels_deep.cu for deep ones.
#pragma once

#include "../common/depth_estimate.h"
#include "chained_launch.cuh"
#include "cuda_check.h"

namespace p3d {
namespace depth_grey_detail {

// A deep grey picture's depth (cuda/kernels_deep.cu).
CudaStatus launch_depth_from_grey_deep(const FrameView &grey, const YuvToRgb &m, ImageView<float> depth,
                                       cudaStream_t stream);

namespace {

constexpr int kGreyX = 32, kGreyY = 8;

__global__ void depth_from_grey_kernel(FrameView grey, YuvToRgb m, int width, int height, ImageView<float> depth) {
  chained_kernel_start();
  const int x = blockIdx.x * kGreyX + threadIdx.x, y = blockIdx.y * kGreyY + threadIdx.y;
  if (x >= width || y >= height) return;
  depth.at(x, y) = depth_from_grey(grey, x, y, m);
}

// depth(x, y) = depth_from_grey(grey, x, y, m) over the pixels both have.
CudaStatus launch_depth_from_grey_of(const FrameView &grey, const YuvToRgb &m, ImageView<float> depth,
                                     cudaStream_t stream) {
  const int w = depth.width < grey.width ? depth.width : grey.width;
  const int h = depth.height < grey.height ? depth.height : grey.height;
  if (depth.empty() || w <= 0 || h <= 0) return {};
  const dim3 grid((w + kGreyX - 1) / kGreyX, (h + kGreyY - 1) / kGreyY);
  P3D_CUDA_TRY(launch_chained(depth_from_grey_kernel, grid, dim3(kGreyX, kGreyY), 0, stream, grey, m, w, h, depth));
  return {};
}

}  // namespace
}  // namespace depth_grey_detail
}  // namespace p3d
