// The pack kernels that every sample depth shares (cuda/pack.cu builds
// them for 8-bit pictures, cuda/kernels_deep.cu for 16-bit ones): a thread
// a packed RGB pixel, or a 2x2 block of 4:2:0 output, through
// pack_pixel_for() of the depth's pixel type. cuda/pack.cu adds the
// vectorised 8-bit kernels.
#pragma once

#include <type_traits>

#include "../common/pack.h"
#include "chained_launch.cuh"
#include "change_gpu.h"
#include "cuda_check.h"

namespace p3d {
namespace pack_detail {

// Everything a launch needs, by value: no device state shared between
// elements, nothing to upload per frame.
struct PackKernelParams {
  PackParams p;
  AnaglyphMatrices am;
  FrameView in;
  FrameView out;
  StageGate gate;  // closed: the adaptive stage keeps this frame (cuda/change_gpu.h)
};

// The 16-bit pictures' pack (cuda/kernels_deep.cu): RGBA64 pairs into
// RGBA64, P010 or I420_10 (pack_args_valid()).
CudaStatus launch_pack_deep(const PackKernelParams &kp, cudaStream_t stream);

constexpr int kBlockX = 32, kBlockY = 8;

namespace {

// One instantiation per input arrangement and pixel type (Rgba, Rgba16):
// the common side-by-side input runs without the code of the others.
template <StereoInput I, class Px>
__global__ void pack_kernel(const PackKernelParams kp) {
  chained_kernel_start();
  if (kp.gate.closed()) return;
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = (gridDim.y - 1 - blockIdx.y) * blockDim.y + threadIdx.y;  // bottom up, as pack_anaglyph_pair_vec
  if (x >= kp.out.width || y >= kp.out.height) return;
  store_pixel(kp.out, x, y, pack_pixel_for<I, Px>(kp.p, kp.am, kp.in, x, y));
}

// 4:2:0 output: one thread per 2x2 block (its four pixels, one chroma pair).
template <StereoInput I, class Px>
__global__ void pack_kernel_yuv(const PackKernelParams kp) {
  chained_kernel_start();
  if (kp.gate.closed()) return;
  const int bx = blockIdx.x * blockDim.x + threadIdx.x;
  const int by = (gridDim.y - 1 - blockIdx.y) * blockDim.y + threadIdx.y;  // bottom up, as pack_anaglyph_pair_vec
  if (2 * bx >= kp.out.width || 2 * by >= kp.out.height) return;
  pack_block_yuv<I, Px>(kp.p, kp.am, kp.in, kp.out, bx, by);
}

// pack_kernel_yuv for 4:2:0 output, else pack_kernel.
template <StereoInput I, class Px>
CudaStatus launch_plain(const PackKernelParams &kp, cudaStream_t stream) {
  const dim3 block(kBlockX, kBlockY);
  if (is_yuv420(kp.out.format)) {
    const int bw = (kp.out.width + 1) / 2, bh = (kp.out.height + 1) / 2;
    const dim3 grid((bw + kBlockX - 1) / kBlockX, (bh + kBlockY - 1) / kBlockY);
    P3D_CUDA_TRY(launch_chained(pack_kernel_yuv<I, Px>, grid, block, 0, stream, kp));
  } else {
    const dim3 grid((kp.out.width + kBlockX - 1) / kBlockX, (kp.out.height + kBlockY - 1) / kBlockY);
    P3D_CUDA_TRY(launch_chained(pack_kernel<I, Px>, grid, block, 0, stream, kp));
  }
  return {};
}

}  // namespace

// f(std::integral_constant<StereoInput, input>{}): the launchers' one
// switch from the run-time arrangement to the kernels' template argument.
template <class F>
CudaStatus with_input(StereoInput input, F &&f) {
  using S = StereoInput;
  switch (input) {
    case S::SideBySideHalf: return f(std::integral_constant<S, S::SideBySideHalf>{});
    case S::TopBottom: return f(std::integral_constant<S, S::TopBottom>{});
    case S::TopBottomHalf: return f(std::integral_constant<S, S::TopBottomHalf>{});
    case S::RowInterleaved: return f(std::integral_constant<S, S::RowInterleaved>{});
    case S::ColumnInterleaved: return f(std::integral_constant<S, S::ColumnInterleaved>{});
    case S::Checkerboard: return f(std::integral_constant<S, S::Checkerboard>{});
    case S::SideBySide:
    default: return f(std::integral_constant<S, S::SideBySide>{});
  }
}

}  // namespace pack_detail
}  // namespace p3d
