// NeighborAverage (common/warp.h) after the row kernel (cuda/warp_rows.cu),
// which wrote each eye's hole mask: Jacobi steps ping-ponging two hole
// masks, in batches of kWarpFillBatch steps; after each batch the host
// reads the per-step fill counts (a stream sync) to stop when no hole is
// left or a step filled nothing (what is left is then painted kFillBlack).
#include <utility>

#include "chained_launch.cuh"
#include "warp_device.cuh"
#include "warp_gpu.h"
#include "warp_internal.h"

namespace p3d {
namespace warp_detail {
namespace {

constexpr int kBlockX = 32;  // NeighborAverage kernels: one warp = one row segment
constexpr int kBlockY = 8;

// One Jacobi step of NeighborAverage over both eyes: reads mask_in and the
// colours of pixels that mask_in says are filled (never written in this
// step), writes the new mask for every pixel.
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
      Rgba c;
      if (neighbour_average(out, eye * W, mask_in + eye * plane, W, W, H, x, y, &c)) {
        store_rgba(out, eye * W + x, y, c);
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

__global__ void paint_holes_kernel(FrameView out, int W, int H, const uint8_t *mask) {
  chained_kernel_start();
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  const int eye = blockIdx.z;
  if (x >= W || y >= H) return;
  if (mask[(static_cast<size_t>(eye) * H + y) * W + x]) store_rgba(out, eye * W + x, y, kFillBlack);
}

dim3 pixel_grid(int W, int H) { return dim3((W + kBlockX - 1) / kBlockX, (H + kBlockY - 1) / kBlockY, 2); }

}  // namespace
}  // namespace warp_detail

using namespace warp_detail;

// NeighborAverage driver: batches of kWarpFillBatch Jacobi steps; the host
// reads the batch's per-step fill counts (one stream sync per batch) and
// stops once no hole is left or a step filled nothing. Steps after such a
// step are no-ops (masks copied), so running the rest of a batch is harmless.
CudaStatus WarpRendererGpu::neighbour_average(const FrameView &out, int W, int H, cudaStream_t stream) {
  uint8_t *counters = counters_.as<uint8_t>();
  auto *filled = reinterpret_cast<unsigned *>(counters + kFilledOffset);
  unsigned long long total = 0;
  P3D_CUDA_TRY(cudaMemcpyAsync(&total, counters + kTotalOffset, sizeof(total), cudaMemcpyDeviceToHost, stream));
  P3D_CUDA_TRY(cudaStreamSynchronize(stream));

  const size_t masks = 2 * static_cast<size_t>(W) * H;
  uint8_t *cur = scratch_.as<uint8_t>(), *next = cur + masks;
  long long remaining = static_cast<long long>(total);
  bool stuck = false;
  while (remaining > 0 && !stuck) {
    P3D_CUDA_TRY(cudaMemsetAsync(filled, 0, sizeof(unsigned) * kWarpFillBatch, stream));
    for (int i = 0; i < kWarpFillBatch; ++i) {
      P3D_CUDA_TRY(launch_chained(neighbour_average_kernel, pixel_grid(W, H), dim3(kBlockX, kBlockY), 0, stream, out, W,
                                  H, cur, next, filled + i));
      std::swap(cur, next);
    }
    unsigned counts[kWarpFillBatch] = {};
    P3D_CUDA_TRY(cudaMemcpyAsync(counts, filled, sizeof(counts), cudaMemcpyDeviceToHost, stream));
    P3D_CUDA_TRY(cudaStreamSynchronize(stream));
    for (int i = 0; i < kWarpFillBatch && !stuck; ++i) {
      remaining -= counts[i];
      stuck = counts[i] == 0;
    }
  }
  if (remaining > 0) {
    P3D_CUDA_TRY(
        launch_chained(paint_holes_kernel, pixel_grid(W, H), dim3(kBlockX, kBlockY), 0, stream, out, W, H, cur));
  }
  return {};
}

}  // namespace p3d
