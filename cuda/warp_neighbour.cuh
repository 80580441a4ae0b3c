// NeighborAverage's kernels (common/warp.h), templates on the pixel type:
// Rgba (cuda/warp_neighbour.cu), Rgba16 (cuda/kernels_deep.cu). The host
// loop that runs them is WarpRendererGpu::neighbour_average.
#pragma once

#include "chained_launch.cuh"
#include "warp_device.cuh"
#include "warp_internal.h"

namespace p3d {
namespace warp_detail {
namespace {

constexpr int kBlockX = 32;  // NeighborAverage kernels: one warp = one row segment
constexpr int kBlockY = 8;

// One Jacobi step of NeighborAverage over both eyes: reads mask_in and the
// colours of pixels that mask_in says are filled (never written in this
// step), writes the new mask for every pixel.
template <class Px>
__global__ void neighbour_average_kernel(FrameView out, int W, int H, const uint8_t *mask_in, uint8_t *mask_out,
                                         unsigned *filled) {
  chained_kernel_start();
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int eye = blockIdx.z;
  bool done = false;
  if (x < W && y < H) {
    const size_t plane = static_cast<size_t>(W) * H;
    const size_t i = eye * plane + static_cast<size_t>(y) * W + x;
    uint8_t still = 0;
    if (mask_in[i]) {
      Px c;
      if (neighbour_average(out, eye * W, mask_in + eye * plane, W, W, H, x, y, &c)) {
        store_pixel(out, eye * W + x, y, c);
        done = true;
      } else {
        still = 1;
      }
    }
    mask_out[i] = still;
  }
  const unsigned ballot = __ballot_sync(kFullMask, done);  // every lane gets here
  if ((threadIdx.x & 31) == 0 && ballot != 0) atomicAdd(filled, static_cast<unsigned>(__popc(ballot)));
}

template <class Px>
__global__ void paint_holes_kernel(FrameView out, int W, int H, const uint8_t *mask) {
  chained_kernel_start();
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int eye = blockIdx.z;
  if (x >= W || y >= H) return;
  if (mask[(static_cast<size_t>(eye) * H + y) * W + x]) store_pixel(out, eye * W + x, y, colour_as<Px>(kFillBlack));
}

dim3 pixel_grid(int W, int H) { return dim3((W + kBlockX - 1) / kBlockX, (H + kBlockY - 1) / kBlockY, 2); }

// One Jacobi step (filled: its fill count), and the paint of the holes
// left, on the pixels of type Px.
template <class Px>
CudaStatus launch_neighbour_step_of(const FrameView &out, int W, int H, const uint8_t *mask_in, uint8_t *mask_out,
                                    unsigned *filled, cudaStream_t stream) {
  P3D_CUDA_TRY(launch_chained(neighbour_average_kernel<Px>, pixel_grid(W, H), dim3(kBlockX, kBlockY), 0, stream, out, W,
                              H, mask_in, mask_out, filled));
  return {};
}
template <class Px>
CudaStatus launch_paint_holes_of(const FrameView &out, int W, int H, const uint8_t *mask, cudaStream_t stream) {
  P3D_CUDA_TRY(
      launch_chained(paint_holes_kernel<Px>, pixel_grid(W, H), dim3(kBlockX, kBlockY), 0, stream, out, W, H, mask));
  return {};
}

}  // namespace
}  // namespace warp_detail
}  // namespace p3d
