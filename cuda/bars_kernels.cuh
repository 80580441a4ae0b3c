// The bar kernels (cuda/bars_gpu.h), built in each translation unit that
// includes this file: cuda/bars.cu for 8-bit frames, cuda/kernels_deep.cu
// for deep ones (whose device code reads their 16-bit samples).
#pragma once

#include "../common/bars.h"
#include "change_gpu.h"
#include "cuda_check.h"

namespace p3d {
namespace bars_detail {

// The deep frames' launches (cuda/kernels_deep.cu).
CudaStatus launch_bar_counts_deep(const FrameView &frame, int luma_threshold, uint32_t *rows, uint32_t *cols,
                                  cudaStream_t stream);
CudaStatus launch_views_outside_deep(const FrameView &src, const YuvToRgb &m, PixelRect active, const FrameView &pair,
                                     cudaStream_t stream, StageGate gate);

namespace {

constexpr int kCountColumns = 128;  // threads a block: one column each
constexpr int kCountRows = 64;      // rows a block walks

// A block counts kCountRows rows of kCountColumns columns: each warp adds
// the bright pixels of its 32 columns of a row to the row's count (one
// atomic a warp and row), each thread its column's to the column's count.
// A plain launch: a memset comes before it.
__global__ void bar_counts_kernel(const FrameView f, int luma_threshold, uint32_t *rows, uint32_t *cols) {
  const int x = blockIdx.x * kCountColumns + threadIdx.x;
  const int y0 = blockIdx.y * kCountRows;
  const int y1 = min(y0 + kCountRows, f.height);
  uint32_t column = 0;
  for (int y = y0; y < y1; ++y) {
    const bool bright = x < f.width && bar_pixel_bright(f, x, y, luma_threshold);
    column += bright;
    const unsigned in_warp = __popc(__ballot_sync(0xffffffffu, bright));
    if ((threadIdx.x & 31) == 0 && in_warp) atomicAdd(rows + y, in_warp);
  }
  if (x < f.width && column) atomicAdd(cols + x, column);
}

// Both views of a pixel outside the rect: the source converted (Px:
// Rgba, or Rgba16 for a deep source).
// A plain launch (after the warp's kernels and copies).
template <class Px>
__global__ void views_outside_kernel(const FrameView src, const YuvToRgb m, const PixelRect active,
                                     const FrameView pair, StageGate gate) {
  if (gate.closed()) return;
  const int x = blockIdx.x * blockDim.x + threadIdx.x;
  const int y = blockIdx.y * blockDim.y + threadIdx.y;
  if (x >= src.width || y >= src.height) return;
  if (x >= active.x0 && x < active.x1 && y >= active.y0 && y < active.y1) return;
  Px c;
  if constexpr (sizeof(Px) == sizeof(Rgba16))
    c = load_rgba16(src, x, y, m);
  else
    c = load_rgba(src, x, y, m);
  store_pixel(pair, x, y, c);
  store_pixel(pair, src.width + x, y, c);
}

// The counts of `frame` into rows (height values) and cols (width), zeroed
// before.
CudaStatus launch_bar_counts_of(const FrameView &frame, int luma_threshold, uint32_t *rows, uint32_t *cols,
                                cudaStream_t stream) {
  const dim3 grid((frame.width + kCountColumns - 1) / kCountColumns, (frame.height + kCountRows - 1) / kCountRows);
  bar_counts_kernel<<<grid, kCountColumns, 0, stream>>>(frame, luma_threshold, rows, cols);
  P3D_CUDA_TRY_LAUNCH(bar_counts_kernel);
  return {};
}

template <class Px>
CudaStatus launch_views_outside_of(const FrameView &src, const YuvToRgb &m, PixelRect active, const FrameView &pair,
                                   cudaStream_t stream, StageGate gate) {
  const dim3 block(32, 8), grid((src.width + 31) / 32, (src.height + 7) / 8);
  views_outside_kernel<Px><<<grid, block, 0, stream>>>(src, m, active, pair, gate);
  P3D_CUDA_TRY_LAUNCH(views_outside_kernel);
  return {};
}

}  // namespace
}  // namespace bars_detail
}  // namespace p3d
