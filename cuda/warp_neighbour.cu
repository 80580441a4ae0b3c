// NeighborAverage (common/warp.h) after the row kernel (cuda/warp_rows.cu),
// which wrote each eye's hole mask: Jacobi steps ping-ponging two hole
// masks, in batches of kWarpFillBatch steps; after each batch the host
// reads the per-step fill counts (a stream sync) to stop when no hole is
// left or a step filled nothing (what is left is then painted kFillBlack).
#include <utility>

#include "warp_gpu.h"
#include "warp_neighbour.cuh"

namespace p3d {
namespace warp_detail {

template <>
CudaStatus launch_neighbour_step<Rgba>(const FrameView &out, int W, int H, const uint8_t *mask_in, uint8_t *mask_out,
                                       unsigned *filled, cudaStream_t stream) {
  return launch_neighbour_step_of<Rgba>(out, W, H, mask_in, mask_out, filled, stream);
}
template <>
CudaStatus launch_paint_holes<Rgba>(const FrameView &out, int W, int H, const uint8_t *mask, cudaStream_t stream) {
  return launch_paint_holes_of<Rgba>(out, W, H, mask, stream);
}

}  // namespace warp_detail

using namespace warp_detail;

// NeighborAverage driver: batches of kWarpFillBatch Jacobi steps; the host
// reads the batch's per-step fill counts (one stream sync per batch) and
// stops once no hole is left or a step filled nothing. Steps after such a
// step are no-ops (masks copied), so running the rest of a batch is harmless.
CudaStatus WarpRendererGpu::neighbour_average(const FrameView &out, int W, int H, cudaStream_t stream) {
  const bool deep = is_deep(out.format);
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
      P3D_CUDA_TRY_STATUS(deep ? launch_neighbour_step<Rgba16>(out, W, H, cur, next, filled + i, stream)
                               : launch_neighbour_step<Rgba>(out, W, H, cur, next, filled + i, stream));
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
  if (remaining > 0)
    P3D_CUDA_TRY_STATUS(deep ? launch_paint_holes<Rgba16>(out, W, H, cur, stream)
                             : launch_paint_holes<Rgba>(out, W, H, cur, stream));
  return {};
}

}  // namespace p3d
